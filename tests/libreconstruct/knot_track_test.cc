#include "libreconstruct/knot_track.h"

#include <gtest/gtest.h>

#include "tests/libreconstruct/rendered_net.h"

namespace netlab::recon {
namespace {

using testing::kCols;
using testing::kRows;
using testing::NetImage;
using testing::RenderNet;

std::vector<std::pair<int, Eigen::Vector2d>> AllKnots(const NetImage& net) {
  std::vector<std::pair<int, Eigen::Vector2d>> knots;
  for (int k = 0; k < kRows * kCols; ++k) knots.emplace_back(k, net.Pixel(k / kCols, k % kCols));
  return knots;
}

// The net moves 2 cm and turns 1.5 degrees between frames (~40 px at the image's scale: a fast
// frame of the flight).
TEST(TrackKnots, FollowsEveryKnotToTheNextFrame) {
  const NetImage a = RenderNet(15.0, 2.0, 1);
  const NetImage b = RenderNet(15.0, 2.0, 2, {}, Eigen::Vector3d(0.0, 0.02, -0.01), 1.5);
  const std::vector<TrackedKnot> tracked = TrackKnots(a.image, b.image, AllKnots(a), kRows, kCols);
  ASSERT_EQ(tracked.size(), static_cast<size_t>(kRows * kCols));
  double worst = 0.0;
  for (const TrackedKnot& t : tracked) {
    EXPECT_TRUE(t.accepted) << "knot " << t.knot << ": " << t.why;
    worst = std::max(worst, (t.px - b.Pixel(t.knot / kCols, t.knot % kCols)).norm());
  }
  EXPECT_LT(worst, 0.1);
}

// In the next frame knot (2,1) lost its yarns to the left and below (hidden): it must not be
// accepted there, and no other knot may take its place.
TEST(TrackKnots, AKnotThatChangedIsLeftForReviewNeverAcceptedWrong) {
  const NetImage a = RenderNet(15.0, 2.0, 3);
  const NetImage b =
      RenderNet(15.0, 2.0, 4, {{8, 9}, {9, 13}}, Eigen::Vector3d(0.0, 0.01, 0.0), 0.5);
  const std::vector<TrackedKnot> tracked = TrackKnots(a.image, b.image, AllKnots(a), kRows, kCols);
  for (const TrackedKnot& t : tracked) {
    const double error = (t.px - b.Pixel(t.knot / kCols, t.knot % kCols)).norm();
    if (t.knot == 9) {
      EXPECT_FALSE(t.accepted);
      EXPECT_FALSE(t.why.empty());
    } else if (t.accepted) {
      EXPECT_LT(error, 0.1) << "knot " << t.knot;
    }
  }
  int accepted = 0;
  for (const TrackedKnot& t : tracked) accepted += t.accepted;
  EXPECT_GE(accepted, 12);  // knots 8 and 13 lost a yarn too
}

}  // namespace
}  // namespace netlab::recon
