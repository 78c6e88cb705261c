// The implicit integrator's two-stage stretching step (stretching: sdirk2, axial_step.h) at its
// own automatic step: a 1 mm Nylon thread's first bending mode against the explicit step's, the
// undamped pendulum's energy and a hard landing.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <utility>
#include <vector>

#include "libnetsim/forces/contact_force.h"
#include "libnetsim/forces/gravity_force.h"
#include "libnetsim/simulation/simulation.h"
#include "tests/libnetsim/test_models.h"

namespace netlab::netsim {
namespace {

using testing::ElasticForces;
using testing::Nylon;
using testing::StraightRod;

SimulationOptions Options(IntegratorType integrator, StretchingScheme stretching) {
  SimulationOptions o;
  o.integrator = integrator;
  o.stretching = stretching;
  return o;
}
const SimulationOptions kExplicit =
    Options(IntegratorType::kSymplecticEuler, StretchingScheme::kBackwardEuler);
const SimulationOptions kTwoStage = Options(IntegratorType::kImplicit, StretchingScheme::kSdirk2);

// A 20 cm, 1 mm Nylon thread clamped level and released under g: it swings about its static
// deflection in its first bending mode (period 0.217 s). The period and the swing of the tip's
// height over 0.7 s.
std::pair<double, double> CantileverMode(SimulationOptions o) {
  auto [model, state] = StraightRod(Nylon(), 0.2, 10, Fixity::kClamped);
  auto forces = ElasticForces(model);
  forces.push_back(std::make_unique<GravityForce>(Vector3d(0, -9.81, 0)));
  o.align_interval = 5e-4;
  Simulation sim(std::move(model), std::move(state), std::move(forces), o);
  const int tip = sim.model().num_nodes() - 1;
  std::vector<double> t, y;
  const long steps = std::lround(0.7 / sim.dt()), every = std::lround(5e-4 / sim.dt());
  for (long k = 0; k <= steps; ++k) {
    if (k % every == 0) {
      t.push_back(sim.state().time);
      y.push_back(sim.state().x[tip].y());
    }
    if (k < steps) {
      EXPECT_TRUE(sim.Step()) << sim.failure()->message;
    }
  }
  return testing::PeriodAndRange(t, y);
}

// Measured: 0.21657 s and 36.12 mm at the implicit step (0.25 ms, 19x explicit's), 0.21665 s and
// 36.14 mm under explicit.
TEST(Stretching, KeepsAThreadsFirstBendingMode) {
  const auto [period, swing] = CantileverMode(kTwoStage);
  const auto [reference_period, reference_swing] = CantileverMode(kExplicit);
  EXPECT_NEAR(reference_period, 0.217, 0.005);
  EXPECT_NEAR(period / reference_period, 1.0, 0.05);
  EXPECT_NEAR(swing / reference_swing, 1.0, 0.05);
}

// The paper's pendulum (30 cm PP yarn, 11 segments, pinned, g along -y), undamped, over 0.5 s at
// the implicit step (35x explicit's): the two-stage step keeps its energy within 0.11 % of what it
// releases, up (0.094 %) and down (backward Euler loses 0.88 %, dynamics_test).
TEST(Stretching, KeepsThePendulumsEnergy) {
  auto [model, state] = StraightRod(testing::PpYarn(), 0.3, 11, Fixity::kPinned);
  auto forces = ElasticForces(model);
  forces.push_back(std::make_unique<GravityForce>(Vector3d(0, -9.81, 0)));
  Simulation sim(std::move(model), std::move(state), std::move(forces), kTwoStage);
  const double e0 = sim.ComputeEnergy().total();
  double worst = 0.0, released = 0.0;
  const long steps = std::lround(0.5 / sim.dt());
  for (long k = 0; k < steps; ++k) {
    ASSERT_TRUE(sim.Step()) << sim.failure()->message;
    const Energy e = sim.ComputeEnergy();
    worst = std::max(worst, std::abs(e.total() - e0));
    released = std::max(released, -e.potential);
  }
  ASSERT_GT(released, 1e-6);
  EXPECT_LT(worst / released, 2e-3);
}

// The hard landing (the paper's net, 0.5 kg corners, onto a sphere at 5 m/s, the contact taken
// within the step) stays stable: with the tension along each stage's midpoint direction instead
// of its predicted end it blew up within 0.09 s.
TEST(Stretching, StaysStableThroughAHardLanding) {
  auto [model, state] = testing::PaperNetFalling(0.5);
  RigidBody sphere;
  sphere.shape = RigidBody::Shape::kSphere;
  sphere.radius = 0.3;
  sphere.friction = 0.3;
  auto forces = ElasticForces(model);
  forces.push_back(std::make_unique<ContactForce>(std::vector<RigidBody>{sphere}));
  Simulation sim(std::move(model), std::move(state), std::move(forces), kTwoStage);
  while (sim.state().time < 0.12) ASSERT_TRUE(sim.Step()) << sim.failure()->message;
  EXPECT_GT(sim.max_penetration(), 0.0);
  EXPECT_LT(sim.max_penetration(), 0.02);
}

}  // namespace
}  // namespace netlab::netsim
