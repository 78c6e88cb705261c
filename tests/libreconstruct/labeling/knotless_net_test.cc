// The labeling tools on a small rendered knotless net: Find Node, Find Path, Fill Grid
// and tracking must never accept a wrong label (more than 2 px from its knot) where a knotless
// net's junctions have no knot ball and its slack links buckle a few pixels from the knot.
//
// Net B of the experiment: 6.25 cm mesh, 1 mm Nylon yarns passing through each other at every
// junction (no knot ball), grey corner masses, slack links. Here a 7 x 7 piece of it, each link
// straight from its knots for part of its length, then shifted sideways in the net's plane by a
// few mm (every second link to the other side); Net A's dyes, royal blue and brown among them a
// twentieth of white in some channels (the dim yarns). Three 16 mm cameras 1.9-2.1 m away see
// links 60-100 px long (the real shot: 68-108 px), as netlab render writes a frame: an RGGB
// mosaic with sensor noise, demosaiced bilinearly, on a dark background. Over four frames the net
// moves a few mm, turns, cups deeper and its links buckle more.
//
// Each link is straight from its knots for 12-33 % of its length (Net B's simulation bends each
// link at its thirds; nearer the knot, the detector's yarn fit reaches past the bend), then
// shifted 1-3 mm sideways, drawn at random per link. Two draws: KnotlessNet, and
// KnotlessNetOtherBuckles, where an edge knot whose inner yarn turns 16-19 degrees for its first
// 8 px was accepted 2.3-2.6 px off by Find Node, Find Path and the cross-check after tracking
// (and another, 23 degrees for 10 px, 3.45 px off by the latter) until the detector checked the
// yarn that alone places an edge knot along its edge (KnotDetectorOptions::lone_bend_px,
// lone_agree_px). Of eight more draws tried then (seeds 1-8), six accepted no wrong label; seed 4
// is the second draw here, and seed 8 accepted knots 2.00-2.05 px off (Find Node, tracking)
// where a yarn turns 16-19 degrees for its first 9-10 px.

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <opencv2/core.hpp>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "calibration/rig.h"
#include "libreconstruct/labeling/knot_detect.h"
#include "libreconstruct/labeling/label_engine.h"
#include "libreconstruct/recording/bayer.h"
#include "libreconstruct/twin/render.h"
#include "tests/libreconstruct/labeling/rendered_net.h"

namespace netlab::recon {
namespace {

constexpr int kRows = 7, kCols = 7, kKnots = kRows * kCols;
constexpr int kFrames = 4;
constexpr double kMesh = 0.0625;  // Net B
constexpr double kWrongPx = 2.0;  // the contract: no accepted label farther off
constexpr int kBorder = 2 * (kRows + kCols) - 4, kInner = kKnots - kBorder;

bool IsCorner(int k) {
  const int r = k / kCols, c = k % kCols;
  return (r == 0 || r == kRows - 1) && (c == 0 || c == kCols - 1);
}
bool IsBorder(int k) {
  const int r = k / kCols, c = k % kCols;
  return r == 0 || c == 0 || r == kRows - 1 || c == kCols - 1;
}

// How the links buckle: each its own fraction of its length straight from its knots, and its own
// sideways shift (m), drawn uniformly from these ranges.
constexpr double kStraightMin = 0.12, kStraightMax = 0.33;
constexpr double kBendMinM = 0.001, kBendMaxM = 0.003;

struct Shot {
  calib::Rig rig;
  std::vector<std::vector<Eigen::Vector3d>> knots;   // [t][k]
  std::vector<std::vector<cv::Mat>> images;          // [camera][t]
  std::vector<std::pair<int, int>> links;            // the knots of each thread
  std::vector<std::vector<ThreadPolyline>> threads;  // [t][link]

  int cameras() const { return static_cast<int>(rig.cameras.size()); }
  Eigen::Vector2d Truth(int c, int t, int k) const {
    return rig.cameras[c].ProjectWorld(knots[t][k]);
  }
};

// The net's pose in frame t: turned, turning 0.3 degrees a frame.
Eigen::Matrix3d Pose(int t) {
  return (Eigen::AngleAxisd(0.3 + 0.005 * t, Eigen::Vector3d::UnitX()) *
          Eigen::AngleAxisd(0.2, Eigen::Vector3d::UnitZ()))
      .toRotationMatrix();
}

// The knots of frame t: a cup 2-3 cm deep at the corners (deeper each frame), moving
// (3, -2, 1.5) mm a frame.
std::vector<Eigen::Vector3d> KnotsAt(int t) {
  const double cup = 0.3 + 0.05 * t;  // 1/m
  std::vector<Eigen::Vector3d> x;
  for (int r = 0; r < kRows; ++r)
    for (int c = 0; c < kCols; ++c) {
      const double y = (c - 3) * kMesh, z = (r - 3) * kMesh;
      x.push_back(Pose(t) * Eigen::Vector3d(cup * (y * y + z * z), y, z) +
                  Eigen::Vector3d(0.003, -0.002, 0.0015) * t);
    }
  return x;
}

// A slack link: straight from each knot for `fraction` of its length, then `bend_m` to the side
// (`side` +-1) in the net's plane (normal `normal`), as rendered_net.h draws it.
ThreadPolyline BuckledLink(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                           const Eigen::Vector3d& normal, double fraction, double bend_m,
                           double side) {
  const Eigen::Vector3d along = b - a;
  const Eigen::Vector3d shift = side * bend_m * along.cross(normal).normalized();
  ThreadPolyline t;
  t.points = {a, a + fraction * along + shift, b - fraction * along + shift, b};
  t.radius = 0.0005;
  return t;
}

// Net B's frames as netlab render writes them (scene white at 0.85 of the sensor's, 1.5 grey
// levels of read noise, RGGB, demosaiced bilinearly).
cv::Mat Photograph(const calib::Camera& camera, const Scene& scene, uint64_t seed) {
  const cv::Mat linear = RenderScene(camera, scene, SceneRenderOptions{}) * 0.85;
  SensorOptions sensor;
  sensor.noise_sigma = 1.5;
  sensor.seed = seed;
  return Demosaic(Expose(linear, camera.intrinsics, sensor), BayerPattern::kRGGB,
                  ColorCorrection{});
}

// `draw`: the seed of the links' buckles.
Shot Render(unsigned draw) {
  Shot shot;
  shot.rig.cameras = {calib::LookAtCamera("a", {-1.9, 0.0, 0.1}, {0, 0, 0}, 16.0, 5.5, 1024),
                      calib::LookAtCamera("b", {-1.95, 0.7, 0.2}, {0, 0, 0}, 16.0, 5.5, 1024),
                      calib::LookAtCamera("c", {-1.95, -0.55, -0.35}, {0, 0, 0}, 16.0, 5.5, 1024)};
  for (int k = 0; k < kKnots; ++k) {
    if (k % kCols + 1 < kCols) shot.links.emplace_back(k, k + 1);
    if (k / kCols + 1 < kRows) shot.links.emplace_back(k, k + kCols);
  }
  // Each link buckles alike in every frame, 5 % more each frame.
  std::mt19937 rng(draw);
  std::uniform_real_distribution<double> fraction(kStraightMin, kStraightMax);
  std::uniform_real_distribution<double> bend(kBendMinM, kBendMaxM);
  std::vector<std::pair<double, double>> buckle;
  for (size_t i = 0; i < shot.links.size(); ++i) buckle.emplace_back(fraction(rng), bend(rng));
  const std::vector<Colour> dyes = testing::NetADyes();
  shot.images.resize(shot.rig.cameras.size());
  for (int t = 0; t < kFrames; ++t) {
    shot.knots.push_back(KnotsAt(t));
    const std::vector<Eigen::Vector3d>& x = shot.knots[t];
    const Eigen::Vector3d normal = Pose(t) * Eigen::Vector3d::UnitX();
    Scene scene;
    for (size_t i = 0; i < shot.links.size(); ++i) {
      const auto [a, b] = shot.links[i];
      scene.threads.push_back(BuckledLink(x[a], x[b], normal, buckle[i].first,
                                          buckle[i].second * (1.0 + 0.05 * t), i % 2 ? -1 : 1));
      scene.threads.back().colour = dyes[i % dyes.size()];
    }
    for (int k = 0; k < kKnots; ++k)
      if (IsCorner(k)) scene.balls.push_back({x[k], 0.01, Colour(0.7f, 0.7f, 0.7f)});
    shot.threads.push_back(scene.threads);
    for (int c = 0; c < shot.cameras(); ++c)
      shot.images[c].push_back(Photograph(shot.rig.cameras[c], scene, 100 * c + t + 1));
  }
  return shot;
}

// Each draw rendered once for all the tests.
const Shot& SlackNet() {
  static const Shot shot = Render(19);
  return shot;
}
const Shot& SlackNetOtherBuckles() {
  static const Shot shot = Render(4);
  return shot;
}

LabelSet Empty(const Shot& shot) {
  std::vector<std::string> names;
  for (const auto& c : shot.rig.cameras) names.push_back(c.name);
  std::vector<int> frames;
  for (int t = 0; t < kFrames; ++t) frames.push_back(t);
  return LabelSet::Empty(kRows, kCols, names, frames);
}

// A person's click on the knot.
Label Accepted(const Eigen::Vector2d& px) {
  Label l;
  l.px = px;
  l.source = LabelSource::kManual;
  l.confidence = 1.0f;
  l.state = LabelState::kAccepted;
  return l;
}

LabelEngine::ImageSource Images(const Shot& shot) {
  return [&shot](int c, int t) { return shot.images[c][t]; };
}

// The engine as for a knotless net (netlab label --knotless): an edge knot is where its straight
// links' colours change.
LabelEngineOptions Knotless() {
  LabelEngineOptions options;
  options.edge_colour_step_px = 1.0;
  return options;
}

// Knot k's yarns in (camera c, frame t), for the failure messages: towards which neighbour,
// turned how far from the line to it at the knot (deg), straight for how long (px).
std::string Yarns(const Shot& shot, int c, int t, int k) {
  std::string out;
  const Eigen::Vector2d o = shot.Truth(c, t, k);
  for (size_t i = 0; i < shot.links.size(); ++i) {
    const auto [a, b] = shot.links[i];
    if (a != k && b != k) continue;
    const std::vector<Eigen::Vector3d>& p = shot.threads[t][i].points;
    const int n = a == k ? b : a;
    const Eigen::Vector2d bend = shot.rig.cameras[c].ProjectWorld(a == k ? p[1] : p[2]) - o;
    const Eigen::Vector2d line = shot.Truth(c, t, n) - o;
    const double turn = std::atan2(line.x() * bend.y() - line.y() * bend.x(), line.dot(bend));
    char s[80];
    std::snprintf(s, sizeof s, " to (%d,%d) %+.0f deg for %.0f px;", n / kCols, n % kCols,
                  turn * 180 / M_PI, bend.norm());
    out += s;
  }
  return out;
}

// Accepted labels against the truth.
struct Tally {
  int accepted = 0;
  int wrong = 0;  // more than kWrongPx from their knot (beside it, or on another)
  int over_1px = 0;
  double worst_px = 0.0;
  std::string wrong_ones;  // which, how far off, and the knot's yarns there

  // `by`: the tool that made the label, when the tally mixes them.
  void Add(const Shot& shot, int c, int t, int k, const Eigen::Vector2d& px, const char* by = "") {
    const Eigen::Vector2d off = px - shot.Truth(c, t, k);
    ++accepted;
    over_1px += off.norm() > 1.0;
    worst_px = std::max(worst_px, off.norm());
    if (off.norm() <= kWrongPx) return;
    ++wrong;
    char s[112];
    std::snprintf(s, sizeof s,
                  "\n  camera %d frame %d knot (%d,%d)%s: %.2f px off (%+.1f, %+.1f), yarns", c, t,
                  k / kCols, k % kCols, by, off.norm(), off.x(), off.y());
    wrong_ones += s + Yarns(shot, c, t, k);
  }
  void Print(const char* what, int of) const {
    std::printf("%s: %d of %d accepted, worst %.2f px, %d over 1 px, %d wrong\n", what, accepted,
                of, worst_px, over_1px, wrong);
  }
};

const char* By(LabelSource source) {
  switch (source) {
    case LabelSource::kFindNode: return " by Find Node";
    case LabelSource::kFindPath: return " by Find Path";
    case LabelSource::kFillGrid: return " by Fill Grid";
    case LabelSource::kTracked: return " tracked";
    default: return "";
  }
}

// The accepted labels of frame t that a tool made (not the person's clicks), of the knots
// `which` picks.
template <typename Which>
Tally ToolLabels(const Shot& shot, const LabelStore& store, int t, Which which) {
  Tally tally;
  for (int c = 0; c < shot.cameras(); ++c)
    for (int k = 0; k < kKnots; ++k) {
      const Label& l = store.at(c, t, k);
      if (which(k) && l.accepted() && l.source != LabelSource::kManual)
        tally.Add(shot, c, t, k, l.px, By(l.source));
    }
  return tally;
}
Tally ToolLabels(const Shot& shot, const LabelStore& store, int t) {
  return ToolLabels(shot, store, t, [](int) { return true; });
}

// Labels of frame t (accepted or for review) of the knots `which` picks.
template <typename Which>
int Labeled(const Shot& shot, const LabelStore& store, int t, Which which) {
  int n = 0;
  for (int c = 0; c < shot.cameras(); ++c)
    for (int k = 0; k < kKnots; ++k) n += which(k) && store.at(c, t, k).present();
  return n;
}

// The person's brush (6 px) on each knot in turn, camera after camera, in the frames `frames`
// of `shot`: each knot found is accepted unless its yarns contradict its labeled neighbours or
// the other cameras place it elsewhere.
// With `neighbours_labeled`, each knot is brushed with only its grid neighbours labeled, by the
// person, in that camera and frame (their yarns' directions known: what confirms a junction
// where no other camera or motion does); otherwise knot after knot into one store, from empty.
Tally FindNodeOnEveryKnot(const Shot& shot, const std::vector<int>& frames, int* found,
                          bool neighbours_labeled = false) {
  LabelStore store(Empty(shot));
  LabelEngine engine(&store, &shot.rig, Images(shot), Knotless());
  Tally tally;
  *found = 0;
  for (int t : frames)
    for (int c = 0; c < shot.cameras(); ++c)
      for (int k = 0; k < kKnots; ++k) {
        if (neighbours_labeled) {
          LabelSet labels = Empty(shot);
          for (int n : GridSlots(kRows, kCols, k))
            if (n >= 0) labels.at(c, t, n) = Accepted(shot.Truth(c, t, n));
          LabelStore alone(std::move(labels));
          LabelEngine brush(&alone, &shot.rig, Images(shot), Knotless());
          if (brush.FindNodeAt(c, t, k, shot.Truth(c, t, k), 6.0).status != FindNodeStatus::kFound)
            continue;
          ++*found;
          if (alone.at(c, t, k).accepted()) tally.Add(shot, c, t, k, alone.at(c, t, k).px);
          continue;
        }
        if (engine.FindNodeAt(c, t, k, shot.Truth(c, t, k), 6.0).status != FindNodeStatus::kFound)
          continue;
        ++*found;
        if (store.at(c, t, k).accepted()) tally.Add(shot, c, t, k, store.at(c, t, k).px);
      }
  return tally;
}

// Find Path along each side of frame 0, between its two corners (the person's clicks), in the
// cameras `cameras`: the junctions of the paths it takes. `taken`: how many.
Tally FindPathAlongTheSides(const Shot& shot, const std::vector<int>& cameras, int* taken) {
  const int corners[4] = {0, kCols - 1, (kRows - 1) * kCols, kKnots - 1};
  Tally tally;
  *taken = 0;
  const std::pair<int, int> sides[4] = {{corners[0], corners[1]},
                                        {corners[2], corners[3]},
                                        {corners[0], corners[2]},
                                        {corners[1], corners[3]}};
  for (int c : cameras)
    for (const auto& [a, b] : sides) {
      const FindPathResult r =
          FindPath(shot.images[c][0], kCols, a, shot.Truth(c, 0, a), b, shot.Truth(c, 0, b));
      if (!r.ok) continue;
      ++*taken;
      for (size_t j = 0; j < r.knots.size(); ++j)
        tally.Add(shot, c, 0, r.knots[j], r.junctions[j].px);
    }
  return tally;
}

// Frame `first` labeled by the person, every knot in every camera; the later frames tracked from
// it, each cross-checked (Fill Grid where tracking lost a knot). Per frame, the tools' labels.
std::vector<Tally> TrackFromALabeledFrame(const Shot& shot, int first) {
  LabelSet labels = Empty(shot);
  for (int c = 0; c < shot.cameras(); ++c)
    for (int k = 0; k < kKnots; ++k) labels.at(c, first, k) = Accepted(shot.Truth(c, first, k));
  LabelStore store(std::move(labels));
  LabelEngine engine(&store, &shot.rig, Images(shot), Knotless());
  engine.TrackFrames(first, kFrames - 1);
  std::vector<Tally> tallies;
  for (int t = first + 1; t < kFrames; ++t) tallies.push_back(ToolLabels(shot, store, t));
  return tallies;
}

// The case is the issue's: links 60-110 px long in the images (measured: 61-98 px).
TEST(KnotlessNet, LinksAreAsLongAsInTheShot) {
  const Shot& shot = SlackNet();
  double shortest = 1e9, longest = 0.0;
  for (int c = 0; c < shot.cameras(); ++c)
    for (int t = 0; t < kFrames; ++t)
      for (const auto& [a, b] : shot.links) {
        const double px = (shot.Truth(c, t, a) - shot.Truth(c, t, b)).norm();
        shortest = std::min(shortest, px), longest = std::max(longest, px);
      }
  std::printf("links %.0f-%.0f px long\n", shortest, longest);
  EXPECT_GT(shortest, 60.0);
  EXPECT_LT(longest, 110.0);
}

// Brushed knot after knot from an empty store, a junction is accepted only where something
// confirms it (LabelEngine::FindNodeAt): 24 of 294 are (worst 0.10 px), the rest kept for review.
// Brushed with its neighbours labeled, 291 of 294 brushes find a junction and 88 are accepted
// (the others kept for review: their yarns, turned by the buckles, miss the labeled neighbours'
// directions by over 10 degrees, or, edge knots, their straight links' colour changes over 1 px
// from the junction), worst 1.09 px. None wrong either way.
TEST(KnotlessNet, FindNodeAcceptsNoWrongKnot) {
  int found = 0;
  const Tally from_empty = FindNodeOnEveryKnot(SlackNet(), {0, kFrames - 1}, &found);
  from_empty.Print("Find Node from an empty store", 2 * 3 * kKnots);
  EXPECT_EQ(from_empty.wrong, 0) << from_empty.wrong_ones;
  EXPECT_GE(from_empty.accepted, 20);
  const Tally tally = FindNodeOnEveryKnot(SlackNet(), {0, kFrames - 1}, &found, true);
  tally.Print("Find Node, neighbours labeled", 2 * 3 * kKnots);
  std::printf("Find Node: %d found\n", found);
  EXPECT_EQ(tally.wrong, 0) << tally.wrong_ones;
  EXPECT_GE(found, 285);
  EXPECT_GE(tally.accepted, 80);
}

// Find Path along each side between its corners: where it takes a path, its junctions are the
// knots between. Measured: 10 of 12 sides taken (the others refused: too few or too many
// junctions found for 5 knots), 50 knots, worst 0.18 px (before the detector's near fit of
// yarns that fit no line over the default strip: 6 sides, worst 0.84 px).
TEST(KnotlessNet, FindPathAlongASideTakesItsKnots) {
  int taken = 0;
  const Tally tally = FindPathAlongTheSides(SlackNet(), {0, 1, 2}, &taken);
  tally.Print("Find Path along the sides", 3 * 4 * (kCols - 2));
  std::printf("Find Path: %d of 12 sides taken\n", taken);
  EXPECT_EQ(tally.wrong, 0) << tally.wrong_ones;
  EXPECT_GE(taken, 9);
}

// The first frame from the four corners clicked in each camera (LabelFirstFrame): the sides,
// then the rows and columns, an inner knot accepted where its row and column agree; every
// junction's yarns must leave towards its neighbours. Measured: 50 of the 60 border knots
// labeled, 19 accepted (the rest kept for review: yarns turned by more than 10 degrees), worst
// 0.18 px; 7 of 75 inner knots accepted (was 30 border labeled, 0 inner).
TEST(KnotlessNet, FindPathFromTheCornersLabelsTheBorder) {
  const Shot& shot = SlackNet();
  LabelSet labels = Empty(shot);
  for (int c = 0; c < shot.cameras(); ++c)
    for (int k = 0; k < kKnots; ++k)
      if (IsCorner(k)) labels.at(c, 0, k) = Accepted(shot.Truth(c, 0, k));
  LabelStore store(std::move(labels));
  LabelEngine engine(&store, &shot.rig, Images(shot), Knotless());
  engine.LabelFirstFrame(0);
  auto side = [](int k) { return IsBorder(k) && !IsCorner(k); };
  auto inner = [](int k) { return !IsBorder(k); };
  const Tally border = ToolLabels(shot, store, 0, side), rest = ToolLabels(shot, store, 0, inner);
  border.Print("Find Path from the corners, border", 3 * (kBorder - 4));
  rest.Print("Find Path from the corners, inner", 3 * kInner);
  const int labeled = Labeled(shot, store, 0, side);
  std::printf("Find Path from the corners: %d of %d border knots labeled\n", labeled,
              3 * (kBorder - 4));
  EXPECT_EQ(border.wrong, 0) << border.wrong_ones;
  EXPECT_EQ(rest.wrong, 0) << rest.wrong_ones;
  EXPECT_GE(labeled, 45);
  EXPECT_GE(border.accepted, 17);
}

// Fill Grid from the border clicked in every camera, in the first and last frames: within 1 px.
// Measured: 13 and 3 of the 75 inner knot views accepted (far from most: a junction whose yarns
// do not leave within 10 degrees of its neighbours' directions is no candidate), worst 0.51 px.
TEST(KnotlessNet, FillGridLabelsNoInnerKnotWrong) {
  const Shot& shot = SlackNet();
  LabelSet labels = Empty(shot);
  for (int t : {0, kFrames - 1})
    for (int c = 0; c < shot.cameras(); ++c)
      for (int k = 0; k < kKnots; ++k)
        if (IsBorder(k)) labels.at(c, t, k) = Accepted(shot.Truth(c, t, k));
  LabelStore store(std::move(labels));
  LabelEngine engine(&store, &shot.rig, Images(shot), Knotless());
  int accepted = 0;
  for (int t : {0, kFrames - 1}) {
    engine.CrossCheck(t);
    const Tally inner = ToolLabels(shot, store, t);
    inner.Print(("Fill Grid, frame " + std::to_string(t)).c_str(), 3 * kInner);
    EXPECT_EQ(inner.wrong, 0) << "frame " << t << inner.wrong_ones;
    EXPECT_LT(inner.worst_px, 1.0) << "frame " << t;
    accepted += inner.accepted;
  }
  EXPECT_GE(accepted, 14);
}

// Measured: 145, 142 and 140 of the 147 knot views accepted in frames 1-3, worst 0.90 px (before
// a junction one yarn short was accepted where its yarns lead to the knot's neighbours: 127, 118
// and 112, worst 1.42 px).
TEST(KnotlessNet, TrackingAcceptsNoWrongKnot) {
  const std::vector<Tally> tallies = TrackFromALabeledFrame(SlackNet(), 0);
  for (size_t i = 0; i < tallies.size(); ++i) {
    tallies[i].Print(("Tracking, frame " + std::to_string(i + 1)).c_str(), 3 * kKnots);
    EXPECT_EQ(tallies[i].wrong, 0) << "frame " << i + 1 << tallies[i].wrong_ones;
  }
  EXPECT_GE(tallies.back().accepted, 130);  // at the end
}

// Another draw of the same slack links, which the lone yarn's checks were made for: in camera b,
// edge knot (3,0)'s inner yarn (to (3,1)) turns 16-19 degrees for its first 8 px, then runs 2-3 px
// aside. The detector fits that yarn mostly past the bend (5-18 px) and puts the junction 2.3 px
// (frame 0) to 2.6 px (frame 3) up the border, along its column's yarn; the near check (3-12 px)
// also reaches past the bend and settles within 1.5 px of it (0.9-1.9 px from the knot), so it
// did not take over. The junction's three yarns still run towards the knot's neighbours. Now a
// junction whose lone yarn's two fits disagree by over lone_agree_px (0.7 px) is refused.
//
// Find Node (brush 6 px at the knot) accepted it 2.28 px off in frame 0 (and 2.55 px off in
// frame 3): brushed in camera b after camera a only and before its neighbours (3,1) and (4,0),
// neither the projection check nor the yarn check had enough to go by. Measured now: 99 of 147
// accepted (103 without the edge colour check), worst 0.88 px.
TEST(KnotlessNetOtherBuckles, FindNodeAcceptsNoWrongKnot) {
  int found = 0;
  const Tally tally = FindNodeOnEveryKnot(SlackNetOtherBuckles(), {0}, &found);
  tally.Print("Find Node, other buckles", 3 * kKnots);
  EXPECT_EQ(tally.wrong, 0) << tally.wrong_ones;
}

// Find Path along column 0 in camera b took the same junction, 2.28 px off (and so did Find
// Path from the corners, LabelFirstFrame, which accepted it). Camera b's sides only (time).
// Measured now: 15 of 20 accepted, worst 0.88 px.
TEST(KnotlessNetOtherBuckles, FindPathAlongASideTakesItsKnots) {
  int taken = 0;
  const Tally tally = FindPathAlongTheSides(SlackNetOtherBuckles(), {1}, &taken);
  tally.Print("Find Path along camera b's sides, other buckles", 4 * (kCols - 2));
  EXPECT_EQ(tally.wrong, 0) << tally.wrong_ones;
}

// Frame 1 labeled by the person, tracked into frames 2 and 3 (rather than from frame 0, to save
// time; from frame 0 the frame 3 label below is accepted alike, the frame 2 one is not).
// Tracking did not accept these junctions (knot (3,0) in frame 3, tracked from frame 0: "moved
// 1.9 px otherwise than its accepted neighbours"), but the cross-check after it did: Fill Grid
// finds the junction as a candidate in camera b and confirms it with the other cameras' accepted
// labels, displaced alike (tracked from frame 0, camera c's label of knot (3,0) in frame 3 was
// accepted 1.2 px off the same way), so the views triangulate consistently. Frame 3: knot (3,0)
// above, 2.55 px off. Frame 2: edge knot (2,0), whose inner yarn turns 23 degrees for its first
// 10 px, 3.45 px off down the border; there the near fit failed, and the default strip's lone
// yarn was refused only once its halves had to agree within 0.7 px (they differ by 0.85 px).
// Measured now: 142 and 140 of 147 accepted, worst 0.90 px.
TEST(KnotlessNetOtherBuckles, TrackingWithItsCrossCheckAcceptsNoWrongKnot) {
  const std::vector<Tally> tallies = TrackFromALabeledFrame(SlackNetOtherBuckles(), 1);
  for (size_t i = 0; i < tallies.size(); ++i) {
    tallies[i].Print(("Tracking, other buckles, frame " + std::to_string(i + 2)).c_str(),
                     3 * kKnots);
    EXPECT_EQ(tallies[i].wrong, 0) << "frame " << i + 2 << tallies[i].wrong_ones;
  }
}

}  // namespace
}  // namespace netlab::recon
