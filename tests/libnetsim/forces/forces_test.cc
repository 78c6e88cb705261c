// Every conservative force must be minus the gradient of the energy it reports, for node positions
// and for body-frame rotations of the segments, checked by central differences on perturbed
// configurations. Damping forces must dissipate.

#include <gtest/gtest.h>

#include <memory>

#include "libnetsim/forces/bend_twist_force.h"
#include "libnetsim/forces/contact_force.h"
#include "libnetsim/forces/drag_force.h"
#include "libnetsim/forces/gravity_force.h"
#include "libnetsim/forces/point_load_force.h"
#include "libnetsim/forces/rotating_frame_force.h"
#include "libnetsim/forces/segment_force.h"
#include "tests/libnetsim/test_models.h"

namespace netlab::netsim {
namespace {

using testing::PpYarn;

struct GradientCase {
  const char* name;
  std::function<std::unique_ptr<Force>(const Model&)> make;
};

// A rod and a small net, bent, stretched and twisted away from rest.
std::pair<Model, State> TestScene() {
  ModelBuilder builder;
  Material m = PpYarn();
  m.stretch_damping = 0.0;
  const int pp = builder.AddMaterial(m);
  RodSpec rod;
  rod.name = "rod";
  rod.material = pp;
  rod.end = Vector3d(0.1, 0.02, 0);
  rod.segments = 5;
  rod.fix_start = Fixity::kClamped;
  builder.AddRod(rod);
  NetSpec net;
  net.name = "net";
  net.material = pp;
  net.rows = net.cols = 2;
  net.mesh = 0.05;
  net.segments_per_link = 3;
  net.center = Vector3d(0, 0, 0.3);
  builder.AddNet(net);
  auto scene = std::move(builder).Build();
  testing::Perturb(scene.second, 2e-3, 0.4, 11);
  return scene;
}

void ExpectForceIsMinusGradient(const Force& force, const Model& model, const State& state) {
  ForceBuffers buffers;
  buffers.Resize(model.num_nodes(), model.num_segments());
  force.Accumulate(model, state, 1e-6, buffers);
  double scale = 1e-12;
  for (const Vector3d& f : buffers.force) scale = std::max(scale, f.norm());
  for (const Vector3d& t : buffers.torque) scale = std::max(scale, t.norm());

  const double h = 1e-7;
  for (int i = 0; i < model.num_nodes(); ++i) {
    for (int k = 0; k < 3; ++k) {
      State plus = state, minus = state;
      plus.x[i][k] += h;
      minus.x[i][k] -= h;
      const double dE = (force.Energy(model, plus) - force.Energy(model, minus)) / (2 * h);
      EXPECT_NEAR(buffers.force[i][k], -dE, 2e-6 * scale)
          << force.name() << " node " << i << " axis " << k;
    }
  }
  const double a = 1e-6;
  for (int j = 0; j < model.num_segments(); ++j) {
    for (int k = 0; k < 3; ++k) {
      State plus = state, minus = state;
      plus.q[j] = plus.q[j] * ExpMap(a * Vector3d::Unit(k));
      minus.q[j] = minus.q[j] * ExpMap(-a * Vector3d::Unit(k));
      const double dE = (force.Energy(model, plus) - force.Energy(model, minus)) / (2 * a);
      EXPECT_NEAR(buffers.torque[j][k], -dE, 2e-6 * scale)
          << force.name() << " segment " << j << " axis " << k;
    }
  }
}

TEST(Forces, StretchIsMinusTheGradientOfItsEnergy) {
  auto [model, state] = TestScene();
  ExpectForceIsMinusGradient(SegmentForce(true, false), model, state);
}

TEST(Forces, CouplingIsMinusTheGradientOfItsEnergy) {
  auto [model, state] = TestScene();
  ExpectForceIsMinusGradient(SegmentForce(false, true), model, state);
}

TEST(Forces, StretchAndCouplingTogetherAreMinusTheGradientOfTheirEnergy) {
  auto [model, state] = TestScene();
  ExpectForceIsMinusGradient(SegmentForce(), model, state);
}

TEST(Forces, BendTwistIsMinusTheGradientOfItsEnergy) {
  auto [model, state] = TestScene();
  // Undamped for the gradient check; a rest curvature exercises phi0.
  for (BendPair& p : model.bend_pairs) p.rest_phi = Vector3d(0.1, -0.05, 0.2);
  ExpectForceIsMinusGradient(BendTwistForce(model), model, state);
}

TEST(Forces, GravityIsMinusTheGradientOfItsEnergy) {
  auto [model, state] = TestScene();
  ExpectForceIsMinusGradient(GravityForce(Vector3d(0.3, -9.81, 1.0)), model, state);
}

TEST(Forces, PointForceIsMinusTheGradientOfItsEnergy) {
  auto [model, state] = TestScene();
  PointLoad load;
  load.index = 3;
  load.vector = Vector3d(1, 2, -3);
  ExpectForceIsMinusGradient(PointLoadForce({load}), model, state);
}

TEST(Forces, CentrifugalForceIsMinusTheGradientOfItsEnergy) {
  auto [model, state] = TestScene();
  for (Vector3d& v : state.v) v.setZero();  // Coriolis vanishes at rest
  ExpectForceIsMinusGradient(RotatingFrameForce(Vector3d(0.3, -0.2, 0.5)), model, state);
}

TEST(Forces, ContactNormalForceIsMinusTheGradientOfItsEnergy) {
  auto [model, state] = TestScene();
  for (Vector3d& v : state.v) v.setZero();
  RigidBody sphere;
  sphere.shape = RigidBody::Shape::kSphere;
  sphere.center = state.x[2] + Vector3d(0.0, 0.0, -0.02);
  sphere.radius = 0.0202;  // node 2 penetrates by ~0.7 mm
  sphere.damping_ratio = 0.0;
  RigidBody box;
  box.shape = RigidBody::Shape::kBox;
  box.center = state.x[8] + Vector3d(0.01, 0.005, 0.0);
  box.half_extents = Vector3d(0.0105, 0.02, 0.02);
  box.orientation = Quaterniond(Eigen::AngleAxisd(0.3, Vector3d(1, 1, 0).normalized()));
  box.damping_ratio = 0.0;
  ContactForce contact({sphere, box});
  contact.SetContactFrequency(2000.0);
  ForceBuffers buffers;
  buffers.Resize(model.num_nodes(), model.num_segments());
  contact.Accumulate(model, state, 1e-6, buffers);
  ASSERT_GT(buffers.max_penetration, 0.0);
  ExpectForceIsMinusGradient(contact, model, state);
}

// The drag evaluated in the segment pass is the same as DragForce's.
TEST(Forces, SegmentPassDragEqualsDragForce) {
  auto [model, state] = TestScene();
  DragOptions drag;
  drag.tangential_coefficient = 0.1;
  ForceBuffers fused, separate;
  fused.Resize(model.num_nodes(), model.num_segments());
  separate.Resize(model.num_nodes(), model.num_segments());
  SegmentForce(true, true, drag).Accumulate(model, state, 0.0, fused);
  SegmentForce().Accumulate(model, state, 0.0, separate);
  DragForce(drag).Accumulate(model, state, 0.0, separate);
  for (int i = 0; i < model.num_nodes(); ++i)
    EXPECT_LT((fused.force[i] - separate.force[i]).norm(), 1e-12);
}

// Damping and drag only ever take energy out: the power F . v + tau . w is negative.
TEST(Forces, DampingAndDragDissipate) {
  auto [model, state] = TestScene();
  for (Segment& s : model.segments) s.stretch_damping = 0.05;
  for (BendPair& p : model.bend_pairs) p.damping = Vector3d(1e-5, 1e-5, 2e-5);
  ForceBuffers elastic, damped;
  elastic.Resize(model.num_nodes(), model.num_segments());
  damped.Resize(model.num_nodes(), model.num_segments());
  SegmentForce(true, false).Accumulate(model, state, 0.0, damped);
  BendTwistForce(model).Accumulate(model, state, 0.0, damped);
  DragOptions drag;
  DragForce(drag).Accumulate(model, state, 0.0, damped);
  // The same without damping and drag, to isolate the dissipative part.
  Model undamped = model;
  for (Segment& s : undamped.segments) s.stretch_damping = 0.0;
  for (BendPair& p : undamped.bend_pairs) p.damping.setZero();
  SegmentForce(true, false).Accumulate(undamped, state, 0.0, elastic);
  BendTwistForce(undamped).Accumulate(undamped, state, 0.0, elastic);
  double power = 0.0;
  for (int i = 0; i < model.num_nodes(); ++i)
    power += (damped.force[i] - elastic.force[i]).dot(state.v[i]);
  for (int j = 0; j < model.num_segments(); ++j)
    power += (damped.torque[j] - elastic.torque[j]).dot(state.w[j]);
  EXPECT_LT(power, 0.0);
}

TEST(Forces, InternalForcesAndTorquesBalance) {
  // Internal forces exert no net force and no net moment about the origin (the clamp is external).
  auto [model, state] = TestScene();
  model.anchors.clear();
  ForceBuffers b;
  b.Resize(model.num_nodes(), model.num_segments());
  SegmentForce().Accumulate(model, state, 0.0, b);
  BendTwistForce(model).Accumulate(model, state, 0.0, b);
  Vector3d net_force = Vector3d::Zero(), net_moment = Vector3d::Zero();
  for (int i = 0; i < model.num_nodes(); ++i) {
    net_force += b.force[i];
    net_moment += state.x[i].cross(b.force[i]);
  }
  for (int j = 0; j < model.num_segments(); ++j) net_moment += state.q[j] * b.torque[j];
  EXPECT_LT(net_force.norm(), 1e-10);
  EXPECT_LT(net_moment.norm(), 1e-10);
}

TEST(Forces, BoxSignedDistanceIsExactOnFacesEdgesAndInside) {
  RigidBody box;
  box.shape = RigidBody::Shape::kBox;
  box.half_extents = Vector3d(1, 2, 3);
  Vector3d n;
  EXPECT_NEAR(box.SignedDistance(Vector3d(1.5, 0, 0), 0.0, &n), 0.5, 1e-15);
  EXPECT_LT((n - Vector3d::UnitX()).norm(), 1e-15);
  EXPECT_NEAR(box.SignedDistance(Vector3d(2, 3, 0), 0.0, &n), std::sqrt(2.0), 1e-15);
  EXPECT_NEAR(box.SignedDistance(Vector3d(0, 0, 2.5), 0.0, &n), -0.5, 1e-15);
  EXPECT_LT((n - Vector3d::UnitZ()).norm(), 1e-15);
  box.velocity = Vector3d(1, 0, 0);  // moving: at t = 2 the centre is at x = 2
  EXPECT_NEAR(box.SignedDistance(Vector3d(3.5, 0, 0), 2.0, &n), 0.5, 1e-15);
}

}  // namespace
}  // namespace netlab::netsim
