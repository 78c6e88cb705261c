// The implicit step keeps the physics the explicit step resolves: a thread's first bending mode
// (frequency and amplitude, slack and taut) and Net A's response to its bending stiffness in
// flight, each against the explicit step (the reference) at its small step.

#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <vector>

#include "libnetsim/forces/drag_force.h"
#include "libnetsim/model/model_builder.h"
#include "libnetsim/simulation/simulation.h"
#include "tests/libnetsim/test_models.h"

namespace netlab::netsim {
namespace {

using testing::ElasticForces;
using testing::Nylon;
using testing::StraightRod;

struct Mode {
  double frequency = 0.0;  // Hz, from the upward zero crossings of the middle node
  double last_peak = 0.0;  // m, the middle node's last peak
  double dt = 0.0;
};

// A 10 cm link of 1 mm Nylon in 4 segments, pinned at both ends and stretched by `strain`, set
// vibrating in its first bending mode (the middle node at 1 cm/s); 0.2 s.
Mode Vibrate(IntegratorType integrator, double safety, double strain) {
  const double length = 0.1, speed = 0.01, duration = 0.2;
  auto [model, state] = StraightRod(Nylon(), length, 4, Fixity::kPinned, Fixity::kPinned);
  for (Vector3d& x : state.x) x.x() *= 1.0 + strain;
  for (size_t i = 0; i < state.x.size(); ++i)
    state.v[i].z() = speed * std::sin(M_PI * state.x[i].x() / state.x.back().x());
  auto forces = ElasticForces(model);
  SimulationOptions o;
  o.integrator = integrator;
  o.safety = safety;
  Simulation sim(std::move(model), std::move(state), std::move(forces), o);
  Mode m;
  m.dt = sim.dt();
  double previous = 0.0, before = 0.0, first_up = -1.0, last_up = -1.0;
  int ups = 0;
  while (sim.state().time < duration) {
    EXPECT_TRUE(sim.Step());
    const double z = sim.state().x[2].z();
    if (previous > before && previous > z) m.last_peak = previous;
    if (previous < 0.0 && z >= 0.0) {
      if (first_up < 0.0) first_up = sim.state().time;
      last_up = sim.state().time;
      ++ups;
    }
    before = previous;
    previous = z;
  }
  if (ups > 1) m.frequency = (ups - 1) / (last_up - first_up);
  return m;
}

// Slack (a bending mode, 49 Hz) and taut (strain 1e-3, 1.6 N: a string mode stiffened by bending,
// 209 Hz): at its own step (30 and 18 times the explicit one) the implicit integrator keeps the
// frequency and the amplitude after 0.2 s within 5 % of the explicit step at half its step.
// Measured: frequency within 0.4 %, amplitude within 0.6 % and 4.4 %. The backward Euler
// stretching step lost the taut mode entirely (last peak 3e-11 m of 7.6e-6 m): its damping of the
// tension's turn, omega h / 4.
TEST(BendingStep, FirstBendingModeKeepsItsFrequencyAndAmplitude) {
  for (const double strain : {0.0, 1e-3}) {
    const Mode reference = Vibrate(IntegratorType::kSymplecticEuler, 0.45, strain);
    const Mode implicit = Vibrate(IntegratorType::kImplicit, 0.0, strain);
    EXPECT_GT(implicit.dt / reference.dt, 30.0) << strain;
    EXPECT_NEAR(implicit.frequency / reference.frequency, 1.0, 0.05) << strain;
    EXPECT_NEAR(implicit.last_peak / reference.last_peak, 1.0, 0.05) << strain;
  }
}

// Net A's net (11 x 11 knots of 1 mm Nylon, 10 cm mesh, 4 segments a link, knot masses, 20 g
// corners leading by 5 cm/s and flying outward, air drag; no gravity, gyro or target) over 0.5 s.
// The knots' positions per frame of 5 ms.
std::vector<std::vector<Vector3d>> Fly(IntegratorType integrator, double bend_factor) {
  ModelBuilderOptions options;
  options.coupling_stiffness_ratio = 100.0 / bend_factor;  // the same penalty kappa
  ModelBuilder builder(options);
  Material nylon = Nylon();
  nylon.bend_stiffness *= bend_factor;
  NetSpec net;
  net.name = "net";
  net.material = builder.AddMaterial(nylon);
  net.rows = net.cols = 11;
  net.mesh = 0.1;
  net.segments_per_link = 4;
  net.knot_mass = 3e-5;
  net.corner_mass = 0.02;
  net.velocity = Vector3d(0.5, 0, 0);
  net.normal = Vector3d::UnitX();
  net.x_axis = Vector3d::UnitY();
  net.corner_velocities = {Vector3d(0.05, -0.01, -0.01), Vector3d(0.05, 0.01, -0.01),
                           Vector3d(0.05, -0.01, 0.01), Vector3d(0.05, 0.01, 0.01)};
  builder.AddNet(net);
  auto [model, state] = std::move(builder).Build();
  DragOptions drag;
  drag.air_density = 1.0;
  drag.drag_coefficient = 1.2;
  auto forces = ElasticForces(model);
  forces.push_back(std::make_unique<DragForce>(drag));
  SimulationOptions o;
  o.integrator = integrator;
  o.align_interval = 0.005;
  Simulation sim(std::move(model), std::move(state), std::move(forces), o);
  std::vector<std::vector<Vector3d>> frames;
  const long per_frame = std::lround(0.005 / sim.dt());
  for (long k = 1; sim.state().time < 0.5 - 0.5 * sim.dt(); ++k) {
    EXPECT_TRUE(sim.Step());
    if (k % per_frame != 0) continue;
    frames.emplace_back();
    for (const Knot& knot : sim.model().knots) frames.back().push_back(sim.state().x[knot.node]);
  }
  return frames;
}

// The knots' response to a 4x bending stiffness (changed run minus nominal run) under the
// implicit step matches the explicit step's within 20 % (RMS of the difference over the RMS of
// the explicit response), the coupling penalty held (docs/simulator.md). Measured: response
// 1.036 mm RMS, relative error 0.163. Smaller nets of the same thread do not: 5 x 5, 7 x 7 and
// 9 x 9 knots part by 1.07, 3.07 and 1.07 of their response (0.35-0.53 mm).
TEST(BendingStep, NetARespondsToTheBendingStiffnessAsTheExplicitStep) {
  const auto e1 = Fly(IntegratorType::kSymplecticEuler, 1.0);
  const auto e4 = Fly(IntegratorType::kSymplecticEuler, 4.0);
  const auto i1 = Fly(IntegratorType::kImplicit, 1.0);
  const auto i4 = Fly(IntegratorType::kImplicit, 4.0);
  ASSERT_EQ(e1.size(), i1.size());
  double reference = 0.0, difference = 0.0;
  for (size_t f = 0; f < e1.size(); ++f)
    for (size_t k = 0; k < e1[f].size(); ++k) {
      const Vector3d r = e4[f][k] - e1[f][k], r_implicit = i4[f][k] - i1[f][k];
      reference += r.squaredNorm();
      difference += (r_implicit - r).squaredNorm();
    }
  EXPECT_GT(std::sqrt(reference / (e1.size() * e1[0].size())), 0.1e-3);  // it responds
  EXPECT_LT(std::sqrt(difference / reference), 0.2);
}

}  // namespace
}  // namespace netlab::netsim
