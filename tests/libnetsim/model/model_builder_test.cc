#include "libnetsim/model/model_builder.h"

#include <gtest/gtest.h>

#include "libnetsim/model/rotation.h"
#include "tests/libnetsim/test_models.h"

namespace netlab::netsim {
namespace {

using testing::PpYarn;

NetSpec PaperNet(int material) {
  NetSpec n;
  n.name = "net";
  n.material = material;
  n.rows = n.cols = 6;
  n.mesh = 0.2;
  n.segments_per_link = 5;
  n.corner_mass = 0.5;
  return n;
}

// Paper section 3: "The whole net is composed of 276 nodes and 300 segments."
TEST(ModelBuilder, PaperNetHas276NodesAnd300Segments) {
  ModelBuilder builder;
  const NetSpec spec = PaperNet(builder.AddMaterial(PpYarn()));
  builder.AddNet(spec);
  auto [model, state] = std::move(builder).Build();
  EXPECT_EQ(model.num_nodes(), 276);
  EXPECT_EQ(model.num_segments(), 300);
  EXPECT_EQ(model.num_knots(), 36);
  EXPECT_EQ(model.nets[0].num_links(), 60);
  // Each link's 5 segments give 4 bend joints: 60 * 4.
  EXPECT_EQ(model.bend_pairs.size(), 240u);
}

TEST(ModelBuilder, NetMassIsThreadPlusCornerMasses) {
  ModelBuilder builder;
  const NetSpec spec = PaperNet(builder.AddMaterial(PpYarn()));
  builder.AddNet(spec);
  auto [model, state] = std::move(builder).Build();
  double total = 0.0;
  for (double m : model.node_mass) total += m;
  const double thread = 60 * 0.2 * 7.1e-4;
  EXPECT_NEAR(total, thread + 4 * 0.5, 1e-12);
  EXPECT_NEAR(model.node_mass[model.KnotNode(0, 0, 0)], 0.5 + 2 * 0.5 * 0.04 * 7.1e-4, 1e-15);
}

TEST(ModelBuilder, KnotsSitOnTheGridAndLinksAreStraight) {
  ModelBuilder builder;
  NetSpec spec = PaperNet(builder.AddMaterial(PpYarn()));
  spec.center = Vector3d(0, 0, 1);
  builder.AddNet(spec);
  auto [model, state] = std::move(builder).Build();
  const Vector3d k00 = state.x[model.KnotNode(0, 0, 0)];
  const Vector3d k05 = state.x[model.KnotNode(0, 0, 5)];
  const Vector3d k50 = state.x[model.KnotNode(0, 5, 0)];
  EXPECT_NEAR((k05 - k00).norm(), 1.0, 1e-12);
  EXPECT_NEAR((k50 - k00).norm(), 1.0, 1e-12);
  EXPECT_NEAR((k05 - k00).dot(Vector3d::UnitX()), 1.0, 1e-12);  // cols along x_axis
  for (const Segment& s : model.segments) {
    EXPECT_NEAR(s.rest_length, 0.04, 1e-12);
    EXPECT_NEAR(state.x[s.node_a].z(), 1.0, 1e-12);
  }
  for (int j = 0; j < model.num_segments(); ++j) {
    const Segment& s = model.segments[j];
    const Vector3d t = (state.x[s.node_b] - state.x[s.node_a]).normalized();
    EXPECT_LT((Director3(state.q[j]) - t).norm(), 1e-12);
  }
}

TEST(ModelBuilder, FoldedNetKeepsLinkLengthsAndKnotSpacing) {
  ModelBuilder builder;
  NetSpec spec = PaperNet(builder.AddMaterial(PpYarn()));
  spec.spread = 0.6;
  builder.AddNet(spec);
  auto [model, state] = std::move(builder).Build();
  const Vector3d k00 = state.x[model.KnotNode(0, 0, 0)];
  const Vector3d k01 = state.x[model.KnotNode(0, 0, 1)];
  EXPECT_NEAR((k01 - k00).norm(), 0.6 * 0.2, 1e-12);
  for (const Segment& s : model.segments)
    EXPECT_NEAR((state.x[s.node_b] - state.x[s.node_a]).norm(), s.rest_length, 1e-12);
  for (const Segment& s : model.segments) EXPECT_NEAR(s.rest_length, 0.04, 1e-12);
  // Every frame follows its segment.
  for (int j = 0; j < model.num_segments(); ++j) {
    const Segment& s = model.segments[j];
    const Vector3d t = (state.x[s.node_b] - state.x[s.node_a]).normalized();
    EXPECT_LT((Director3(state.q[j]) - t).norm(), 1e-12);
  }
}

TEST(ModelBuilder, SpreadBelowWhatTheLinksCanFoldToIsRejected) {
  ModelBuilder builder;
  NetSpec spec = PaperNet(builder.AddMaterial(PpYarn()));
  spec.spread = 0.5 * MinimumSpread(5);
  EXPECT_THROW(builder.AddNet(spec), std::invalid_argument);
}

TEST(ModelBuilder, CornerVelocitiesAddToTheNetVelocity) {
  ModelBuilder builder;
  NetSpec spec = PaperNet(builder.AddMaterial(PpYarn()));
  spec.velocity = Vector3d(0.5, 0, 0);
  spec.corner_velocities[3] = Vector3d(0, 0.2, 0.1);
  builder.AddNet(spec);
  auto [model, state] = std::move(builder).Build();
  EXPECT_LT((state.v[model.KnotNode(0, 5, 5)] - Vector3d(0.5, 0.2, 0.1)).norm(), 1e-15);
  EXPECT_LT((state.v[model.KnotNode(0, 2, 2)] - Vector3d(0.5, 0, 0)).norm(), 1e-15);
}

TEST(ModelBuilder, RodEndsArePinnedOrClamped) {
  ModelBuilder builder;
  RodSpec rod;
  rod.name = "yarn";
  rod.material = builder.AddMaterial(PpYarn());
  rod.end = Vector3d(0.3, 0, 0);
  rod.segments = 11;
  rod.fix_start = Fixity::kClamped;
  rod.fix_end = Fixity::kPinned;
  builder.AddRod(rod);
  auto [model, state] = std::move(builder).Build();
  EXPECT_EQ(model.num_nodes(), 12);
  EXPECT_EQ(model.node_inv_mass[0], 0.0);
  EXPECT_EQ(model.node_inv_mass[11], 0.0);
  EXPECT_GT(model.node_inv_mass[5], 0.0);
  // The clamp is a bending joint over half the first segment to its fixed initial frame.
  ASSERT_EQ(model.anchors.size(), 1u);
  EXPECT_EQ(model.anchors[0].segment, 0);
  EXPECT_NEAR(model.anchors[0].inv_length, 2.0 / (0.3 / 11), 1e-9);
  EXPECT_LT(model.anchors[0].frame.angularDistance(state.q[0]), 1e-15);
}

TEST(ModelBuilder, BadSpecificationsNameTheProblem) {
  ModelBuilder builder;
  const int pp = builder.AddMaterial(PpYarn());
  RodSpec rod;
  rod.name = "yarn";
  rod.material = pp;
  rod.segments = 0;
  try {
    builder.AddRod(rod);
    FAIL() << "expected an exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("rod 'yarn'"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("segments"), std::string::npos);
  }
  Material bad = PpYarn();
  bad.name = "bad";
  bad.bend_stiffness = -1;
  EXPECT_THROW(builder.AddMaterial(bad), std::invalid_argument);
}

TEST(ModelBuilder, DescribesNodesBySurroundingStructure) {
  ModelBuilder builder;
  const NetSpec spec = PaperNet(builder.AddMaterial(PpYarn()));
  builder.AddNet(spec);
  auto [model, state] = std::move(builder).Build();
  EXPECT_EQ(model.DescribeNode(model.KnotNode(0, 2, 3)), "net 'net' knot (2,3)");
  EXPECT_EQ(model.DescribeNode(36), "net 'net' link (0,0)-(0,1) node 1");
  EXPECT_EQ(model.DescribeSegment(0), "net 'net' link (0,0)-(0,1) segment 0");
}

}  // namespace
}  // namespace netlab::netsim
