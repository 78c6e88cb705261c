#include "libreconstruct/labeling/knot_track.h"

#include <gtest/gtest.h>

#include <cmath>
#include <opencv2/imgproc.hpp>

#include "tests/libreconstruct/labeling/rendered_net.h"

namespace netlab::recon {
namespace {

using testing::kCols;
using testing::kRows;
using testing::NetImage;
using testing::RenderNet;
using testing::RenderNetOptions;

std::vector<std::pair<int, Eigen::Vector2d>> AllKnots(const NetImage& net) {
  std::vector<std::pair<int, Eigen::Vector2d>> knots;
  for (int k = 0; k < kRows * kCols; ++k) knots.emplace_back(k, net.Pixel(k / kCols, k % kCols));
  return knots;
}

// The tracking tests' net: turned 15 degrees, 2 grey levels of noise.
RenderNetOptions Tilted(uint64_t seed) {
  RenderNetOptions o;
  o.tilt_deg = 15.0;
  o.noise_grey = 2.0;
  o.seed = seed;
  return o;
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

// Two frames as a shot's camera records them (demosaiced Bayer mosaics, Net A's dyes, knot balls,
// corner masses), the net 2.5 m away moving 1 cm (13 px): every knot is accepted, the corners on
// their masses. Measured: worst 0.056 px.
TEST(TrackKnots, FollowsTheKnotsOfDemosaicedFramesAndTheCornersOnTheirMasses) {
  RenderNetOptions o;
  o.distance_m = 2.5;
  o.tilt_deg = 12.0;
  o.noise_grey = 1.0;
  o.dyes = testing::NetADyes();
  o.knot_radius_m = 0.0015;
  o.corner_radius_m = 0.01;
  o.bayer = true;
  o.seed = 5;
  const NetImage a = RenderNet(o);
  o.seed = 6;
  o.offset = Eigen::Vector3d(0.0, 0.01, 0.004);
  o.spin_deg = 0.5;
  const NetImage b = RenderNet(o);
  const std::vector<TrackedKnot> tracked = TrackKnots(a.image, b.image, AllKnots(a), kRows, kCols);
  for (const TrackedKnot& t : tracked) {
    EXPECT_TRUE(t.accepted) << "knot " << t.knot << ": " << t.why;
    EXPECT_LT((t.px - b.Pixel(t.knot / kCols, t.knot % kCols)).norm(), 0.15) << "knot " << t.knot;
  }
}

// Knot (1,1) shows no yarn in the first frame (hidden), so it has no flow; in the next it is
// whole. Its four neighbours move as one: it is accepted on their motion, and only then.
TEST(TrackKnots, AcceptsAKnotWithoutFlowOnItsNeighboursCommonMotion) {
  const NetImage a = RenderNet(15.0, 0.0, 7, {{1, 5}, {4, 5}, {5, 6}, {5, 9}});
  const NetImage b = RenderNet(15.0, 2.0, 8, {}, Eigen::Vector3d(0.0, 0.005, 0.0), 0.0);
  TrackOptions options;
  const std::vector<TrackedKnot> tracked =
      TrackKnots(a.image, b.image, AllKnots(a), kRows, kCols, options);
  EXPECT_TRUE(tracked[5].accepted) << tracked[5].why;
  EXPECT_LT((tracked[5].px - b.Pixel(1, 1)).norm(), 0.1);
  options.max_neighbour_spread_px = 0.0;
  const std::vector<TrackedKnot> strict =
      TrackKnots(a.image, b.image, AllKnots(a), kRows, kCols, options);
  EXPECT_FALSE(strict[5].accepted);
  EXPECT_NE(strict[5].why.find("flow lost"), std::string::npos) << strict[5].why;
}

// In the next frame knot (1,1) moved 1.5 mm (about 3 px) besides the net's motion: its junction
// is found, but a knot does not move otherwise than its neighbours between frames (on Net A at
// most 0.6 px), so it is left for review; its neighbours, whose expected motion it enters, stay
// accepted. Without the check it is accepted where its junction is.
TEST(TrackKnots, AKnotThatMovedOtherwiseThanItsNeighboursIsLeftForReview) {
  RenderNetOptions o = Tilted(9);
  const NetImage a = RenderNet(o);
  o.seed = 10;
  o.offset = Eigen::Vector3d(0.0, 0.005, -0.003);
  o.moved = {{5, Eigen::Vector3d(0.0, 0.0015, 0.0)}};
  const NetImage b = RenderNet(o);
  ASSERT_GT((b.Pixel(1, 1) - a.Pixel(1, 1) - (b.Pixel(1, 2) - a.Pixel(1, 2))).norm(), 2.5);
  const std::vector<TrackedKnot> tracked = TrackKnots(a.image, b.image, AllKnots(a), kRows, kCols);
  for (const TrackedKnot& t : tracked) {
    if (t.knot == 5) continue;
    EXPECT_TRUE(t.accepted) << "knot " << t.knot << ": " << t.why;
    EXPECT_LT((t.px - b.Pixel(t.knot / kCols, t.knot % kCols)).norm(), 0.1) << "knot " << t.knot;
  }
  EXPECT_FALSE(tracked[5].accepted);
  EXPECT_NE(tracked[5].why.find("otherwise than its accepted neighbours"), std::string::npos)
      << tracked[5].why;
  TrackOptions options;
  options.max_relative_motion_px = 0.0;
  const std::vector<TrackedKnot> unchecked =
      TrackKnots(a.image, b.image, AllKnots(a), kRows, kCols, options);
  EXPECT_TRUE(unchecked[5].accepted) << unchecked[5].why;
  EXPECT_LT((unchecked[5].px - b.Pixel(1, 1)).norm(), 0.1);
}

// In the next frame the link between knots (1,1) and (1,2) is gone (a dim dye fading into the
// background): each of the two inner knots shows three yarns. Each yarn leads to one of the
// knot's labeled neighbours, so both are accepted, where they are. Without a direction for every
// yarn found (a neighbour not labeled) or with the rule off, they are left for review.
TEST(TrackKnots, AcceptsAKnotOneYarnShortWhoseYarnsLeadToItsNeighbours) {
  RenderNetOptions o = Tilted(12);
  const NetImage a = RenderNet(o);
  o.seed = 13;
  o.offset = Eigen::Vector3d(0.0, 0.004, -0.002);
  o.missing = {{5, 6}};
  const NetImage b = RenderNet(o);
  const std::vector<TrackedKnot> tracked = TrackKnots(a.image, b.image, AllKnots(a), kRows, kCols);
  for (const TrackedKnot& t : tracked) {
    EXPECT_TRUE(t.accepted) << "knot " << t.knot << ": " << t.why;
    EXPECT_LT((t.px - b.Pixel(t.knot / kCols, t.knot % kCols)).norm(), 0.1) << "knot " << t.knot;
  }
  // Knot (2,1) not labeled in the first frame: knot (1,1)'s yarn down leads nowhere known.
  std::vector<std::pair<int, Eigen::Vector2d>> without;
  for (const auto& k : AllKnots(a))
    if (k.first != 9) without.push_back(k);
  const std::vector<TrackedKnot> partial = TrackKnots(a.image, b.image, without, kRows, kCols);
  EXPECT_FALSE(partial[5].accepted);
  EXPECT_NE(partial[5].why.find("has 3 yarns, the knot 4"), std::string::npos) << partial[5].why;
  TrackOptions strict;
  strict.max_yarn_angle_deg = 0.0;
  const std::vector<TrackedKnot> off =
      TrackKnots(a.image, b.image, AllKnots(a), kRows, kCols, strict);
  EXPECT_FALSE(off[5].accepted);
  EXPECT_FALSE(off[6].accepted);
}

// The same two knots one yarn short, but none of their neighbours can be tracked (each lost two
// of its yarns): the directions of their yarns still lead to the neighbours' labels in the first
// frame, but no accepted neighbour moved with them to check the junction's place. In a folded
// net such junctions (a yarn beside the knot's own, another layer's crossing) were accepted
// 2.1-2.7 px off: they are left for review.
TEST(TrackKnots, AKnotOneYarnShortWithoutAcceptedNeighboursIsLeftForReview) {
  RenderNetOptions o = Tilted(12);
  const NetImage a = RenderNet(o);
  o.seed = 13;
  o.offset = Eigen::Vector3d(0.0, 0.004, -0.002);
  // (1,1)-(1,2) gone; knots 1, 2, 4, 7, 9 and 10 around them two yarns short each.
  o.missing = {{5, 6}, {0, 1},  {1, 2}, {2, 3},  {0, 4},   {4, 8},
               {3, 7}, {7, 11}, {8, 9}, {9, 13}, {10, 11}, {10, 14}};
  const NetImage b = RenderNet(o);
  const std::vector<TrackedKnot> tracked = TrackKnots(a.image, b.image, AllKnots(a), kRows, kCols);
  for (const int k : {1, 2, 4, 7, 9, 10}) EXPECT_FALSE(tracked[k].accepted) << "knot " << k;
  for (const int k : {5, 6}) {
    EXPECT_TRUE(tracked[k].one_yarn_short) << "knot " << k << ": " << tracked[k].why;
    EXPECT_FALSE(tracked[k].accepted) << "knot " << k;
  }
  // Knot (1,2)'s flow held (knot (1,1)'s did not, and its neighbours' motion could not
  // predict it): its junction passed every other test.
  EXPECT_NE(tracked[6].why.find("no accepted neighbour moved with it"), std::string::npos)
      << tracked[6].why;
}

// Knot (1,1) tracked alone, its neighbours labeled in both frames (a person's fixes) and given as
// known motions: they check it as accepted neighbours would. Moved 1.5 mm besides the net, it is
// left for review; where it moved with the net, it is accepted. A tracked knot that lands on a
// known knot's place is not.
TEST(TrackKnots, KnownNeighbourMotionsCheckAKnotTrackedAlone) {
  RenderNetOptions o = Tilted(9);
  const NetImage a = RenderNet(o);
  o.seed = 10;
  o.offset = Eigen::Vector3d(0.0, 0.005, -0.003);
  const NetImage b = RenderNet(o);
  o.moved = {{5, Eigen::Vector3d(0.0, 0.0015, 0.0)}};
  const NetImage moved = RenderNet(o);
  std::vector<KnownMotion> known;
  for (const int n : {1, 4, 6, 9, 0, 2, 8, 10})
    known.push_back({n, a.Pixel(n / kCols, n % kCols), b.Pixel(n / kCols, n % kCols)});
  const std::vector<std::pair<int, Eigen::Vector2d>> alone = {{5, a.Pixel(1, 1)}};
  const TrackedKnot with_net = TrackKnots(a.image, b.image, alone, kRows, kCols, {}, known)[0];
  EXPECT_TRUE(with_net.accepted) << with_net.why;
  EXPECT_LT((with_net.px - b.Pixel(1, 1)).norm(), 0.1);
  const TrackedKnot off = TrackKnots(a.image, moved.image, alone, kRows, kCols, {}, known)[0];
  EXPECT_FALSE(off.accepted);
  EXPECT_NE(off.why.find("otherwise than its accepted neighbours"), std::string::npos) << off.why;
  // Knot (1,2) tracked from knot (1,1)'s place: it lands where (1,1) is known to be.
  const std::vector<std::pair<int, Eigen::Vector2d>> wrong = {{6, a.Pixel(1, 1)}};
  std::vector<KnownMotion> with_5 = {{5, a.Pixel(1, 1), b.Pixel(1, 1)}};
  const TrackedKnot taken = TrackKnots(a.image, b.image, wrong, kRows, kCols, {}, with_5)[0];
  EXPECT_FALSE(taken.accepted);
}

// Knot (1,1) just behind the edge of a grey body in the next frame: the body covers its yarn to
// (1,2) from 1 px beside the knot on (a wedge around that yarn, so the others stay in view). The
// three yarns left make a junction there, each leading to a neighbour, and its neighbours moved
// with it; but a knot at a body's edge with a yarn missing may be behind the body: left for
// review. Without the check it is accepted.
TEST(TrackKnots, AJunctionAYarnShortAtTheEdgeOfABodyIsLeftForReview) {
  RenderNetOptions o = Tilted(12);
  const NetImage a = RenderNet(o);
  o.seed = 13;
  o.offset = Eigen::Vector3d(0.0, 0.004, -0.002);
  NetImage b = RenderNet(o);
  const Eigen::Vector2d knot = b.Pixel(1, 1);
  const Eigen::Vector2d u = (b.Pixel(1, 2) - knot).normalized(), v(-u.y(), u.x());
  auto at = [&](double along, double across) {
    const Eigen::Vector2d p = knot + along * u + across * v;
    return cv::Point(cvRound(p.x()), cvRound(p.y()));
  };
  const std::vector<cv::Point> wedge = {at(1.5, -8.0), at(1.5, 8.0), at(70.0, 40.0),
                                        at(70.0, -40.0)};
  cv::fillConvexPoly(b.image, wedge, cv::Scalar::all(150));
  const std::vector<TrackedKnot> tracked = TrackKnots(a.image, b.image, AllKnots(a), kRows, kCols);
  EXPECT_FALSE(tracked[5].accepted);
  EXPECT_NE(tracked[5].why.find("edge of the target"), std::string::npos) << tracked[5].why;
  TrackOptions unchecked;
  unchecked.body_edge_px = 0.0;
  const std::vector<TrackedKnot> plain =
      TrackKnots(a.image, b.image, AllKnots(a), kRows, kCols, unchecked);
  EXPECT_TRUE(plain[5].accepted) << plain[5].why;
  EXPECT_LT((plain[5].px - knot).norm(), 0.5);
}

// In the next frame knot (1,1) is a blob with four yarns leaving it, none of them its own (yarns
// bunched in a fold): only a corner knot sits in a blob (its corner mass), so the blob is not
// taken for the knot, though as many yarns leave it as the knot has.
TEST(TrackKnots, ABlobAtAnInnerKnotIsNotTheKnot) {
  RenderNetOptions o = Tilted(14);
  const NetImage a = RenderNet(o);
  o.seed = 15;
  o.offset = Eigen::Vector3d(0.0, 0.004, -0.002);
  o.missing = {{1, 5}, {4, 5}, {5, 6}, {5, 9}};
  NetImage b = RenderNet(o);
  const Eigen::Vector2d knot = b.Pixel(1, 1);
  const cv::Point centre(cvRound(knot.x()), cvRound(knot.y()));
  cv::circle(b.image, centre, 8, cv::Scalar::all(200), cv::FILLED, cv::LINE_AA);
  // A pinwheel: each yarn leaves the blob's rim along its tangent, so no two of them meet.
  for (int i = 0; i < 4; ++i) {
    const double angle = i * M_PI / 2, ca = std::cos(angle), sa = std::sin(angle);
    const cv::Point rim(cvRound(knot.x() + 6 * ca), cvRound(knot.y() + 6 * sa));
    const cv::Point out(cvRound(rim.x - 30 * sa), cvRound(rim.y + 30 * ca));
    cv::line(b.image, rim, out, cv::Scalar::all(200), 2, cv::LINE_AA);
  }
  const std::vector<TrackedKnot> tracked = TrackKnots(a.image, b.image, AllKnots(a), kRows, kCols);
  EXPECT_FALSE(tracked[5].accepted);
  EXPECT_NE(tracked[5].why.find("blob"), std::string::npos) << tracked[5].why;
}

// Where a net folds, its mesh is seen sheared and another layer's yarns run close beside a
// knot's own. Here the mesh is turned 45 degrees in its plane, then 72 away from the camera (its
// links meet at 33-36 degrees in the image), with a yarn 11 px beside each inner knot's row.
RenderNetOptions Sheared(uint64_t seed) {
  RenderNetOptions o = Tilted(seed);
  o.in_plane_deg = 45.0;
  o.tilt_deg = 72.0;
  return o;
}

// Inner knot k's image angles towards its four neighbours (left, right, up, down).
std::vector<double> LinkAngles(const NetImage& net, int k) {
  std::vector<double> angles;
  for (const auto& [dr, dc] :
       {std::pair(0, -1), std::pair(0, 1), std::pair(-1, 0), std::pair(1, 0)}) {
    const Eigen::Vector2d d =
        net.Pixel(k / kCols + dr, k % kCols + dc) - net.Pixel(k / kCols, k % kCols);
    angles.push_back(std::atan2(d.y(), d.x()));
  }
  return angles;
}

// The other layer: a yarn along each inner knot's row, 11 px to its side.
void AddLayerBeside(NetImage* net) {
  for (const int k : {5, 6, 9, 10}) {
    const Eigen::Vector2d knot = net->Pixel(k / kCols, k % kCols);
    const Eigen::Vector2d row = (net->Pixel(k / kCols, k % kCols + 1) - knot).normalized();
    const Eigen::Vector2d p = knot + 11.0 * Eigen::Vector2d(-row.y(), row.x());
    cv::line(net->image, cv::Point(cvRound(p.x() - 60 * row.x()), cvRound(p.y() - 60 * row.y())),
             cv::Point(cvRound(p.x() + 60 * row.x()), cvRound(p.y() + 60 * row.y())),
             cv::Scalar(200, 200, 60), 2, cv::LINE_AA);
  }
}

// There the detector's rings, which cross the other layer's yarn, find no junction; the knot's
// yarns fitted along its links as they ran in the frame before place it.
TEST(TrackKnots, FitsTheYarnsAlongTheLinksWhereAFoldHidesTheJunction) {
  NetImage a = RenderNet(Sheared(16));
  RenderNetOptions o = Sheared(17);
  o.offset = Eigen::Vector3d(0.0, 0.003, -0.002);
  NetImage b = RenderNet(o);
  AddLayerBeside(&a);
  AddLayerBeside(&b);
  const int inner[] = {5, 6, 9, 10};
  for (const int k : inner) {
    const std::vector<double> links = LinkAngles(b, k);
    const double angle = std::abs(std::remainder(links[1] - links[3], M_PI)) * 180 / M_PI;
    EXPECT_LT(angle, 40.0) << "knot " << k << ": the mesh is not sheared enough for the test";
    EXPECT_TRUE(FindNode(b.image, b.Pixel(k / kCols, k % kCols), 3.0).candidates.empty())
        << "knot " << k << ": the rings find a junction; the test needs none";
  }
  const std::vector<TrackedKnot> tracked = TrackKnots(a.image, b.image, AllKnots(a), kRows, kCols);
  TrackOptions rings_only;
  rings_only.fit_along_gap_px = 0.0;
  const std::vector<TrackedKnot> plain =
      TrackKnots(a.image, b.image, AllKnots(a), kRows, kCols, rings_only);
  for (const int k : inner) {
    EXPECT_TRUE(tracked[k].accepted) << "knot " << k << ": " << tracked[k].why;
    EXPECT_LT((tracked[k].px - b.Pixel(k / kCols, k % kCols)).norm(), 0.5) << "knot " << k;
    EXPECT_FALSE(plain[k].accepted) << "knot " << k;
    EXPECT_NE(plain[k].why.find("no junction"), std::string::npos) << plain[k].why;
  }
}

// The yarns are fitted only along the directions given: along the knot's links it is found
// from a pixel off; along directions the yarns do not take (a neighbour's label from another
// knot), or midway along a link (one yarn), nothing is.
TEST(FitAlongLinks, FindsTheJunctionAlongItsLinksOnly) {
  NetImage net = RenderNet(Sheared(18));
  AddLayerBeside(&net);
  const Eigen::Vector2d knot = net.Pixel(1, 1);
  std::vector<Eigen::Vector2d> links;
  for (const double a : LinkAngles(net, 5)) links.emplace_back(std::cos(a), std::sin(a));
  const std::optional<Junction> j =
      FitAlongLinks(net.image, knot + Eigen::Vector2d(1.0, -1.0), links, 5.0, {});
  ASSERT_TRUE(j.has_value());
  EXPECT_GE(j->branches, 3);  // all but one of four (the other layer may spoil one strip's fit)
  EXPECT_LT((j->px - knot).norm(), 0.3);
  const Eigen::Rotation2Dd turn(40.0 * M_PI / 180.0);
  std::vector<Eigen::Vector2d> turned;
  for (const Eigen::Vector2d& d : links) turned.push_back(turn * d);
  EXPECT_FALSE(FitAlongLinks(net.image, knot, turned, 5.0, {}).has_value());
  EXPECT_FALSE(
      FitAlongLinks(net.image, 0.5 * (knot + net.Pixel(1, 2)), links, 5.0, {}).has_value());
}

}  // namespace
}  // namespace netlab::recon
