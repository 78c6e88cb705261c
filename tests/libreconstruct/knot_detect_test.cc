#include "libreconstruct/knot_detect.h"

#include <gtest/gtest.h>

#include <random>

#include "tests/libreconstruct/rendered_net.h"

namespace netlab::recon {
namespace {

using testing::NetImage;
using testing::RenderNet;
using testing::kCols;
using testing::kRows;

// Measured: worst 0.043 px (no tilt) and 0.060 px (25 degrees), most below 0.01 px.
TEST(FindNode, FindsEveryKnotToATenthOfAPixel) {
  for (double tilt : {0.0, 25.0}) {
    const NetImage net = RenderNet(tilt, 0.0, 1);
    double worst = 0.0;
    for (int r = 0; r < kRows; ++r)
      for (int c = 0; c < kCols; ++c) {
        const Eigen::Vector2d truth = net.Pixel(r, c);
        // The brush a little off the knot, as a hand puts it.
        const FindNodeResult found = FindNode(net.image, truth + Eigen::Vector2d(4, -3), 15);
        ASSERT_EQ(found.status, FindNodeStatus::kFound)
            << "knot " << r << "," << c << " tilt " << tilt << ": " << found.why;
        const int degree = (r > 0) + (r + 1 < kRows) + (c > 0) + (c + 1 < kCols);
        EXPECT_EQ(found.knot.branches, degree) << r << "," << c;
        worst = std::max(worst, (found.knot.px - truth).norm());
        EXPECT_GT(found.knot.confidence, 0.5) << r << "," << c;
      }
    EXPECT_LT(worst, 0.1) << "tilt " << tilt;
  }
}

TEST(FindNode, SaysNoneOnAPlainYarnAndSeveralWhenTwoKnotsAreInside) {
  const NetImage net = RenderNet(10.0, 0.0, 2);
  const Eigen::Vector2d mid = 0.5 * (net.Pixel(1, 1) + net.Pixel(1, 2));
  const FindNodeResult yarn = FindNode(net.image, mid, 20);
  EXPECT_EQ(yarn.status, FindNodeStatus::kNone) << yarn.candidates.size();
  const FindNodeResult empty = FindNode(net.image, {20, 20}, 15);
  EXPECT_EQ(empty.status, FindNodeStatus::kNone);
  const double spacing = (net.Pixel(1, 1) - net.Pixel(1, 2)).norm();
  const FindNodeResult two = FindNode(net.image, mid, 0.5 * spacing + 10);
  EXPECT_EQ(two.status, FindNodeStatus::kSeveral);
  EXPECT_EQ(two.candidates.size(), 2u);
}

TEST(FindNode, StaysAccurateWithSensorNoise) {
  const NetImage net = RenderNet(15.0, 4.0, 3);
  double ss = 0.0;
  int n = 0;
  for (int r = 0; r < kRows; ++r)
    for (int c = 0; c < kCols; ++c) {
      const FindNodeResult found = FindNode(net.image, net.Pixel(r, c), 15);
      ASSERT_EQ(found.status, FindNodeStatus::kFound) << r << "," << c << ": " << found.why;
      ss += (found.knot.px - net.Pixel(r, c)).squaredNorm();
      ++n;
    }
  EXPECT_LT(std::sqrt(ss / n), 0.1);  // measured 0.037 px at 4 grey levels of noise
}

TEST(FindPath, LabelsTheKnotsBetweenTwoKnotsOfARowOrColumn) {
  const NetImage net = RenderNet(20.0, 2.0, 4);
  // Row 1, from (1,0) to (1,3): knots (1,1) and (1,2) in that order.
  FindPathResult row = FindPath(net.image, kCols, 4, net.Pixel(1, 0), 7, net.Pixel(1, 3));
  ASSERT_TRUE(row.ok) << row.why;
  ASSERT_EQ(row.knots, (std::vector<int>{5, 6}));
  EXPECT_LT((row.junctions[0].px - net.Pixel(1, 1)).norm(), 0.1);
  EXPECT_LT((row.junctions[1].px - net.Pixel(1, 2)).norm(), 0.1);
  // Column 2, from the bottom up: (2,2), (1,2).
  FindPathResult column = FindPath(net.image, kCols, 14, net.Pixel(3, 2), 2, net.Pixel(0, 2));
  ASSERT_TRUE(column.ok) << column.why;
  EXPECT_EQ(column.knots, (std::vector<int>{10, 6}));
  EXPECT_LT((column.junctions[0].px - net.Pixel(2, 2)).norm(), 0.1);
  // Neighbours: nothing between, nothing to find.
  FindPathResult next = FindPath(net.image, kCols, 5, net.Pixel(1, 1), 6, net.Pixel(1, 2));
  EXPECT_TRUE(next.ok) << next.why;
  EXPECT_TRUE(next.knots.empty());
}

TEST(FindPath, RefusesWhenTheJunctionsDoNotMatchTheGrid) {
  // Knot (1,1) lost its vertical yarns: the row passes straight through it.
  const NetImage net = RenderNet(20.0, 0.0, 5, {{1, 5}, {5, 9}});
  FindPathResult row = FindPath(net.image, kCols, 4, net.Pixel(1, 0), 7, net.Pixel(1, 3));
  EXPECT_FALSE(row.ok);
  EXPECT_NE(row.why.find("found 1 junctions"), std::string::npos) << row.why;
  EXPECT_TRUE(row.knots.empty());
  FindPathResult diagonal = FindPath(net.image, kCols, 0, net.Pixel(0, 0), 5, net.Pixel(1, 1));
  EXPECT_FALSE(diagonal.ok);
  EXPECT_NE(diagonal.why.find("not in one row or column"), std::string::npos);
}

}  // namespace
}  // namespace netlab::recon
