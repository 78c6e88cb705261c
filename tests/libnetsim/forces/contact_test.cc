// Contact with rigid targets against closed forms, and the net-capture hard case.

#include <gtest/gtest.h>

#include <cmath>

#include "libnetsim/forces/bend_twist_force.h"
#include "libnetsim/forces/contact_force.h"
#include "libnetsim/forces/gravity_force.h"
#include "libnetsim/forces/segment_force.h"
#include "libnetsim/simulation/simulation.h"
#include "tests/libnetsim/test_models.h"

namespace netlab::netsim {
namespace {

using testing::PpYarn;

std::vector<std::unique_ptr<Force>> Forces(const Model& model, const Vector3d& g,
                                           std::vector<RigidBody> bodies) {
  std::vector<std::unique_ptr<Force>> forces;
  forces.push_back(std::make_unique<SegmentForce>());
  forces.push_back(std::make_unique<BendTwistForce>(model));
  forces.push_back(std::make_unique<GravityForce>(g));
  forces.push_back(std::make_unique<ContactForce>(std::move(bodies)));
  return forces;
}

// A short horizontal thread at a height z above the plane z = 0.
std::pair<Model, State> ThreadAbovePlane(double z, const Vector3d& velocity = Vector3d::Zero()) {
  ModelBuilder builder;
  RodSpec rod;
  rod.name = "thread";
  rod.material = builder.AddMaterial(PpYarn());
  rod.start = Vector3d(0, 0, z);
  rod.end = Vector3d(0.05, 0, z);
  rod.segments = 4;
  rod.velocity = velocity;
  builder.AddRod(rod);
  return std::move(builder).Build();
}

RigidBody Floor(double friction = 0.0) {
  RigidBody plane;
  plane.name = "floor";
  plane.shape = RigidBody::Shape::kPlane;
  plane.normal = Vector3d::UnitZ();
  plane.friction = friction;
  return plane;
}

class Contact : public ::testing::TestWithParam<IntegratorType> {
 protected:
  SimulationOptions Options() const {
    SimulationOptions o;
    o.integrator = GetParam();
    return o;
  }
};

// At rest on a plane each node sinks until its penalty carries its weight: with the automatic
// stiffness k = m omega_c^2, the depth is g / omega_c^2 whatever the node's mass.
TEST_P(Contact, ThreadRestsOnAPlaneAtThePenaltyDepth) {
  auto [model, state] = ThreadAbovePlane(0.0005);  // touching: node radius 0.5 mm
  auto forces = Forces(model, Vector3d(0, 0, -9.81), {Floor()});
  Simulation sim(std::move(model), std::move(state), std::move(forces), Options());
  ASSERT_TRUE(sim.Relax(2.0, 1e-12, 1e-12));
  const double omega_c = sim.stability().contact_omega;
  ASSERT_GT(omega_c, 0.0);
  const double depth = 9.81 / (omega_c * omega_c);
  for (const Vector3d& x : sim.state().x) EXPECT_NEAR(x.z(), 0.0005 - depth, 1e-3 * depth);
}

// Sliding with Coulomb friction: a thread thrown along a plane at v0 stops after v0^2 / (2 mu g).
TEST_P(Contact, FrictionStopsASlidingThreadAtTheCoulombDistance) {
  const double v0 = 0.5, mu = 0.3, g = 9.81;
  auto [model, state] = ThreadAbovePlane(0.0005 - 9.81 / 1e8, Vector3d(v0, 0, 0));
  auto forces = Forces(model, Vector3d(0, 0, -g), {Floor(mu)});
  Simulation sim(std::move(model), std::move(state), std::move(forces), Options());
  const double x0 = sim.state().x[0].x();
  ASSERT_TRUE(sim.Advance(std::lround(1.5 * v0 / (mu * g) / sim.dt())));
  const double expected = v0 * v0 / (2.0 * mu * g);
  EXPECT_NEAR((sim.state().x[0].x() - x0) / expected, 1.0, 0.02);
  EXPECT_LT(sim.state().v[2].norm(), 1e-3);  // and it is at rest
}

// A moving body carries what it touches: a plane rising at 0.2 m/s lifts a resting thread, which
// ends up moving with it (no tunnelling, penetration bounded by v / omega_c).
TEST_P(Contact, MovingPlanePushesTheThreadAlong) {
  auto [model, state] = ThreadAbovePlane(0.01);
  RigidBody lift = Floor();
  lift.velocity = Vector3d(0, 0, 0.2);
  auto forces = Forces(model, Vector3d(0, 0, -9.81), {lift});
  Simulation sim(std::move(model), std::move(state), std::move(forces), Options());
  ASSERT_TRUE(sim.Advance(std::lround(0.3 / sim.dt())));
  for (const Vector3d& v : sim.state().v) EXPECT_NEAR(v.z(), 0.2, 0.01);
  const double t = sim.state().time;
  for (const Vector3d& x : sim.state().x) EXPECT_GT(x.z() - 0.2 * t, 0.0);
}

// A thread dropped onto a box lands on its top face, one node radius above it.
TEST_P(Contact, ThreadLandsOnTheTopOfABox) {
  auto [model, state] = ThreadAbovePlane(0.3);
  RigidBody box;
  box.shape = RigidBody::Shape::kBox;
  box.center = Vector3d(0.025, 0, 0.1);
  box.half_extents = Vector3d(0.1, 0.1, 0.1);
  box.damping_ratio = 1.0;
  auto forces = Forces(model, Vector3d(0, 0, -9.81), {box});
  Simulation sim(std::move(model), std::move(state), std::move(forces), Options());
  ASSERT_TRUE(sim.Advance(std::lround(0.6 / sim.dt())));
  for (const Vector3d& x : sim.state().x) EXPECT_NEAR(x.z(), 0.2005, 1e-4);
}

// Hard case: the paper's net (6 x 6 knots, 5 segments per link, 0.5 kg corners) thrown at a rigid
// sphere at 5 m/s. Stable and finite; no node centre enters the sphere; the deepest penetration
// stays below the impact bound v / omega_c plus the chord sagitta l^2 / (8 R): once the net
// wraps, its tension presses the nodes in, by about as much as the straight segments between
// nodes already cut into the sphere (measured 0.58 mm against 0.28 + 0.67 mm).
TEST_P(Contact, NetHittingASphereAt5MetresPerSecondStaysStable) {
  auto [model, state] = testing::PaperNetFalling(0.32);
  RigidBody sphere;
  sphere.shape = RigidBody::Shape::kSphere;
  sphere.radius = 0.3;
  sphere.friction = 0.3;
  auto forces = Forces(model, Vector3d(0, 0, -9.81), {sphere});
  Simulation sim(std::move(model), std::move(state), std::move(forces), Options());
  double closest = 1.0;
  const long steps = std::lround(0.15 / sim.dt());
  for (long k = 0; k < steps; ++k) {
    ASSERT_TRUE(sim.Step()) << sim.failure()->message;
    if (k % 20 == 0)
      for (const Vector3d& x : sim.state().x) closest = std::min(closest, x.norm() - 0.3);
  }
  for (const Vector3d& x : sim.state().x) ASSERT_TRUE(x.allFinite());
  const double impact = 5.5 / sim.stability().contact_omega;  // impact speed + free fall
  const double sagitta = 0.04 * 0.04 / (8.0 * 0.3);
  EXPECT_GT(sim.max_penetration(), 0.0);  // it did hit
  EXPECT_LT(sim.max_penetration(), impact + sagitta);
  EXPECT_GT(closest, 0.0);  // node centres never inside the sphere
}

INSTANTIATE_TEST_SUITE_P(Integrators, Contact, testing::AllIntegrators(),
                         testing::IntegratorTestName);

}  // namespace
}  // namespace netlab::netsim
