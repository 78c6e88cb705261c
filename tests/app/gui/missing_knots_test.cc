// The review queue's missing knots without a window (app/gui/document/missing_knots.h): a 3 x 3
// net 1.5 m in front of three cameras that label it exactly, a fourth that sees part of it and a
// fifth that looks away. Listed where two other cameras put the knot (to the picture's outer
// edge, and beyond it by the point's error), where one camera's ray and the grid neighbours do
// (to 1 px beyond the edge), never where a
// disagreeing pair or two facing cameras alone would, nor where the target hides it; off the list
// once labeled or marked hidden, back on undo; the incremental count always equals a count from
// scratch.

#include "app/gui/document/missing_knots.h"

#include <gtest/gtest.h>

#include <QCoreApplication>
#include <QSignalSpy>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <set>
#include <string>
#include <vector>

#include "app/gui/document/project.h"
#include "common/errors.h"

namespace netlab::gui {
namespace {

constexpr int kRows = 3, kCols = 3, kKnots = kRows * kCols, kFrames = 4;

// Cameras a, b, c see the whole net; "edge" is aimed 0.2 m beside it (its far column falls
// outside the picture); "back" stands beyond the net looking away from it.
struct Scene {
  calib::Rig rig;
  std::vector<std::vector<Eigen::Vector3d>> knots;  // [t][k], m

  Scene() {
    rig.cameras = {calib::LookAtCamera("a", {-1.5, 0.0, 0.0}, {0, 0, 0}, 16.0, 5.5, 1024),
                   calib::LookAtCamera("b", {-1.4, 0.55, 0.1}, {0, 0, 0}, 16.0, 5.5, 1024),
                   calib::LookAtCamera("c", {-1.35, -0.45, -0.3}, {0, 0, 0}, 16.0, 5.5, 1024),
                   calib::LookAtCamera("edge", {-1.5, 0.2, 0.0}, {0, 0.2, 0}, 16.0, 5.5, 1024),
                   calib::LookAtCamera("back", {1.0, 0.0, 0.0}, {3, 0, 0}, 16.0, 5.5, 1024)};
    for (int t = 0; t < kFrames; ++t) {
      std::vector<Eigen::Vector3d> x;
      for (int k = 0; k < kKnots; ++k)
        x.emplace_back(0.01 * t, (k % kCols - 1) * 0.1, (k / kCols - 1) * 0.1);
      knots.push_back(x);
    }
  }
  Eigen::Vector2d Truth(int c, int t, int k) const {
    return rig.cameras[c].ProjectWorld(knots[t][k]);
  }
  // Inside the picture's outer edge (-0.5 .. 1023.5 px); no knot of the scene lies within 1 px
  // beyond it (AKnotTwoOtherCamerasSeeIsListedWhereTheyPutIt checks).
  bool InPicture(int c, int t, int k) const {
    const Eigen::Vector2d q = Truth(c, t, k);
    return q.allFinite() && q.minCoeff() >= -0.5 && q.maxCoeff() <= 1023.5;
  }
  bool NearTheEdge(int c, int t, int k) const {
    const Eigen::Vector2d q = Truth(c, t, k);
    return q.allFinite() && !InPicture(c, t, k) && q.minCoeff() >= -1.5 && q.maxCoeff() <= 1024.5;
  }
  // Cameras a, b and c label every knot exactly (accepted); edge and back label nothing.
  recon::LabelSet Labels() const {
    recon::LabelSet set =
        recon::LabelSet::Empty(kRows, kCols, {"a", "b", "c", "edge", "back"}, {0, 1, 2, 3});
    for (int c = 0; c < 3; ++c)
      for (int t = 0; t < kFrames; ++t)
        for (int k = 0; k < kKnots; ++k) set.at(c, t, k) = Accepted(Truth(c, t, k));
    return set;
  }
  static recon::Label Accepted(const Eigen::Vector2d& px) {
    recon::Label l;
    l.px = px;
    l.source = recon::LabelSource::kManual;
    l.confidence = 1.0f;
    l.state = recon::LabelState::kAccepted;
    return l;
  }
};

const std::vector<int> kRigIndex = {0, 1, 2, 3, 4};

// The edge camera's knots inside its picture, as (camera, t, knot) in the queue's order.
std::vector<LabelKey> EdgeItems(const Scene& scene, int t) {
  std::vector<LabelKey> items;
  for (int k = 0; k < kKnots; ++k)
    if (scene.InPicture(3, t, k)) items.emplace_back(3, t, k);
  return items;
}

// Every frame row counted from scratch.
std::vector<LabelKey> FromScratch(const LabelDocument& doc, const calib::Rig& rig) {
  std::vector<LabelKey> items;
  for (int t = 0; t < kFrames; ++t)
    for (const MissingKnot& m : FindMissingKnots(doc.labels(), rig, kRigIndex, t))
      items.emplace_back(m.camera, m.t, m.knot);
  return items;
}

TEST(MissingKnots, AKnotTwoOtherCamerasSeeIsListedWhereTheyPutIt) {
  const Scene scene;
  // The edge camera sees part of the net: some knots in its picture, some not.
  ASSERT_GT(EdgeItems(scene, 1).size(), 0u);
  ASSERT_LT(EdgeItems(scene, 1).size(), static_cast<size_t>(kKnots));
  for (int t = 0; t < kFrames; ++t)
    for (int k = 0; k < kKnots; ++k) ASSERT_FALSE(scene.NearTheEdge(3, t, k)) << t << " " << k;
  recon::LabelSet labels = scene.Labels();
  labels.at(2, 1, 4) = recon::Label{};  // camera c lost the centre knot in frame row 1
  LabelDocument doc(labels, "/nonexistent/labels.h5");
  const MissingKnots missing(&doc, &scene.rig, kRigIndex);
  // Row 1: c's knot 4, then the edge camera's knots in its picture; never the back camera's.
  std::vector<LabelKey> want;
  for (int t = 0; t < kFrames; ++t) {
    if (t == 1) want.emplace_back(2, 1, 4);
    for (const LabelKey& key : EdgeItems(scene, t)) want.push_back(key);
  }
  EXPECT_EQ(missing.Items(), want);
  EXPECT_EQ(missing.size(), static_cast<int>(want.size()));
  const MissingKnot* m = missing.Find(2, 1, 4);
  ASSERT_NE(m, nullptr);
  EXPECT_LT((m->expected_px - scene.Truth(2, 1, 4)).norm(), 1e-6);
  EXPECT_EQ(m->seen_in, (std::vector<int>{0, 1}));
  EXPECT_LT(m->rms_px, 1e-6);
  char where[64];
  std::snprintf(where, sizeof where, "(%.1f, %.1f)", scene.Truth(2, 1, 4).x(),
                scene.Truth(2, 1, 4).y());
  EXPECT_EQ(missing.Reason(2, 1, 4), std::string("no label; seen in a, b; expected near ") + where);
  EXPECT_EQ(missing.Reason(2, 0, 4), "");
  EXPECT_EQ(missing.Frames(), (std::set<int>{0, 1, 2, 3}));
}

// The edge camera moved (its principal point) so that knot k of row t falls at x = want_x.
calib::Rig WithKnotAt(const Scene& scene, int t, int k, double want_x) {
  calib::Rig rig = scene.rig;
  calib::CameraIntrinsics& in = rig.cameras[3].intrinsics;
  in.cx += want_x - rig.cameras[3].ProjectWorld(scene.knots[t][k]).x();
  return rig;
}

bool Lists(const recon::LabelSet& labels, const calib::Rig& rig, int t, int k,
           const MissingKnotsOptions& options = {}) {
  for (const MissingKnot& m : FindMissingKnots(labels, rig, kRigIndex, t, options))
    if (m.camera == 3 && m.knot == k) return true;
  return false;
}

// The image spans -0.5 .. width - 0.5 px (pixel centres at integers, as `netlab render` and the
// true labels count a knot in the picture). A point the cameras place is listed beyond that edge
// only as far as its error reaches (3 sigma of its projection for 0.1 px of label noise): a knot
// just inside the edge can be placed a little beyond it, but one placed further out is out of
// view, and listing it would cost the person a look and a D (the held-out shot's true labels had
// 10 such knots 0.4-1.0 px beyond the edge listed). WhyNotMissing says why.
TEST(MissingKnots, AKnotBeyondThePicturesEdgeIsListedOnlyWithinItsPointsError) {
  const Scene scene;
  const recon::LabelSet labels = scene.Labels();  // a, b and c label every knot exactly
  const int t = 1, k = 4;
  // The error of a, b and c's point along the edge camera's x axis, 3 sigma for 0.1 px.
  std::vector<recon::Observation> views;
  for (int c = 0; c < 3; ++c) views.push_back({c, labels.at(c, t, k).px});
  const auto projected =
      recon::ProjectEstimate(scene.rig, 3, recon::TriangulatePoint(scene.rig, views));
  ASSERT_TRUE(projected.has_value());
  const double slack = 3.0 * 0.1 * std::sqrt(projected->unit_covariance(0, 0));
  ASSERT_GT(slack, 0.05);
  ASSERT_LT(slack, 0.6);
  struct Case {
    double beyond;  // px beyond the outer edge (negative: inside)
    bool listed;
  };
  for (const Case& want : {Case{-0.2, true}, Case{0.8 * slack, true}, Case{slack + 0.3, false},
                           Case{0.9, false}, Case{1.2, false}})
    for (const double x : {1023.5 + want.beyond, -0.5 - want.beyond}) {
      const calib::Rig rig = WithKnotAt(scene, t, k, x);
      ASSERT_NEAR(rig.cameras[3].ProjectWorld(scene.knots[t][k]).x(), x, 1e-6);
      EXPECT_EQ(Lists(labels, rig, t, k), want.listed) << x;
      const std::string why = recon::WhyNotMissing(labels, rig, kRigIndex, 3, t, k);
      if (want.listed)
        EXPECT_EQ(why, "") << x;
      else
        EXPECT_NE(why.find("outside the image"), std::string::npos) << x << ": " << why;
      // Labels taken to be worse (1 px) carry the point's error to 1 px beyond the edge.
      MissingKnotsOptions rough_labels;
      rough_labels.label_sigma_px = 1.0;
      EXPECT_EQ(Lists(labels, rig, t, k, rough_labels), want.beyond <= 1.0) << x;
      // With nothing beyond the edge taken, only the points inside it.
      MissingKnotsOptions strict;
      strict.beyond_edge_px = 0.0;
      EXPECT_EQ(Lists(labels, rig, t, k, strict), want.beyond <= 0.0) << x;
    }
}

// A point from one camera's ray at the depth of its grid neighbours has no error known to the
// pixel: it is listed to beyond_edge_px (1 px) beyond the picture's edge.
TEST(MissingKnots, ARoughPointIsListedToOnePixelBeyondThePicturesEdge) {
  const Scene scene;
  recon::LabelSet labels = scene.Labels();
  const int t = 1, k = 4;
  labels.at(1, t, k) = labels.at(2, t, k) = recon::Label{};  // a alone labels knot 4
  for (const double beyond : {-0.2, 0.8, 1.2})
    for (const double x : {1023.5 + beyond, -0.5 - beyond}) {
      const calib::Rig rig = WithKnotAt(scene, t, k, x);
      bool listed = false;
      for (const MissingKnot& m : FindMissingKnots(labels, rig, kRigIndex, t))
        if (m.camera == 3 && m.knot == k) {
          listed = true;
          EXPECT_EQ(m.basis, recon::MissingBasis::kNeighbours);
          EXPECT_NEAR(m.expected_px.x(), x, 1e-6);
        }
      EXPECT_EQ(listed, beyond <= 1.0) << x;
    }
}

TEST(MissingKnots, ALabelOrAHiddenMarkTakesItOffTheListAndUndoPutsItBack) {
  const Scene scene;
  recon::LabelSet labels = scene.Labels();
  labels.at(2, 1, 4) = recon::Label{};
  LabelDocument doc(labels, "/nonexistent/labels.h5");
  const MissingKnots missing(&doc, &scene.rig, kRigIndex);
  QSignalSpy changed(&missing, &MissingKnots::changed);
  ASSERT_NE(missing.Find(2, 1, 4), nullptr);
  // Labeled (where the other cameras put it): off the list; row 1 counted again, and the rows
  // whose points its motion gives (motion_rows either side: all four here).
  doc.Apply("Find Node", {{2, 1, 4, Scene::Accepted(scene.Truth(2, 1, 4))}});
  EXPECT_EQ(missing.Find(2, 1, 4), nullptr);
  ASSERT_EQ(changed.count(), 1);
  EXPECT_EQ(changed.last().at(0).value<QList<int>>(), QList<int>({0, 1, 2, 3}));
  EXPECT_EQ(missing.Items(), FromScratch(doc, scene.rig));
  doc.undo_stack()->undo();
  EXPECT_NE(missing.Find(2, 1, 4), nullptr);
  // Marked hidden: off the list; undo puts it back.
  doc.Apply("Mark hidden", {{2, 1, 4, recon::Label::Hidden()}});
  EXPECT_EQ(missing.Find(2, 1, 4), nullptr);
  EXPECT_EQ(missing.Items(), FromScratch(doc, scene.rig));
  doc.undo_stack()->undo();
  EXPECT_NE(missing.Find(2, 1, 4), nullptr);
  // A label under review is a review item, not a missing knot.
  recon::Label doubtful = Scene::Accepted(scene.Truth(2, 1, 4));
  doubtful.state = recon::LabelState::kNeedsReview;
  doc.Apply("Track", {{2, 1, 4, doubtful}});
  EXPECT_EQ(missing.Find(2, 1, 4), nullptr);
  EXPECT_EQ(missing.Items(), FromScratch(doc, scene.rig));
}

TEST(MissingKnots, AKnotOneCameraSeesIsListedOnItsRayWhereItsNeighboursPutIt) {
  const Scene scene;
  recon::LabelSet labels = scene.Labels();
  // Knot 4 of row 0 labeled by camera a alone (b and c lost it): a's ray at the depth of its
  // neighbours, where it is (the net is flat: the midpoints are exact).
  labels.at(1, 0, 4) = labels.at(2, 0, 4) = recon::Label{};
  LabelDocument doc(labels, "/nonexistent/labels.h5");
  const MissingKnots missing(&doc, &scene.rig, kRigIndex);
  for (int c : {1, 2, 3}) {
    const MissingKnot* m = missing.Find(c, 0, 4);
    ASSERT_NE(m, nullptr) << "camera " << c;
    EXPECT_EQ(m->basis, recon::MissingBasis::kNeighbours);
    EXPECT_EQ(m->seen_in, (std::vector<int>{0}));
    EXPECT_LT((m->expected_px - scene.Truth(c, 0, 4)).norm(), 1e-6) << "camera " << c;
  }
  EXPECT_EQ(missing.Find(4, 0, 4), nullptr);  // the back camera looks away
  const std::string reason = missing.Reason(1, 0, 4);
  EXPECT_EQ(reason.rfind("no label; seen in a, at the depth its grid neighbours give; expected "
                         "near (",
                         0),
            0u)
      << reason;
}

TEST(MissingKnots, ADisagreeingPairPlacesNothingItsNeighboursDo) {
  const Scene scene;
  recon::LabelSet labels = scene.Labels();
  // Knot 3 of row 2: c lost it, and b's label is 8 px off a's epipolar line (b's image y; the
  // pair's baseline runs along image x).
  labels.at(2, 2, 3) = recon::Label{};
  labels.at(1, 2, 3).px.y() += 8.0;
  // Knot 7 of row 3: a, b, c label it, c 8 px off: the edge camera is not told where they put it.
  ASSERT_TRUE(scene.InPicture(3, 3, 7));
  labels.at(2, 3, 7).px.y() += 8.0;
  LabelDocument doc(labels, "/nonexistent/labels.h5");
  const MissingKnots missing(&doc, &scene.rig, kRigIndex);
  // Both listed where the grid neighbours put them (knot 3 is an edge knot: one grid line).
  for (const auto& [c, t, k] : {LabelKey{2, 2, 3}, LabelKey{3, 3, 7}}) {
    const MissingKnot* m = missing.Find(c, t, k);
    ASSERT_NE(m, nullptr) << "camera " << c << " knot " << k;
    EXPECT_EQ(m->basis, recon::MissingBasis::kNeighbours);
    EXPECT_LT((m->expected_px - scene.Truth(c, t, k)).norm(), 1e-6);
  }
  EXPECT_EQ(missing.Reason(3, 3, 7).rfind("no label; its grid neighbours put it near (", 0), 0u);
}

TEST(MissingKnots, NothingPlacesAKnotOfANetOnlyOneCameraLabeled) {
  const Scene scene;
  recon::LabelSet labels = scene.Labels();
  for (int t = 0; t < kFrames; ++t)
    for (int k = 0; k < kKnots; ++k) labels.at(1, t, k) = labels.at(2, t, k) = recon::Label{};
  LabelDocument doc(labels, "/nonexistent/labels.h5");
  const MissingKnots missing(&doc, &scene.rig, kRigIndex);
  EXPECT_EQ(missing.size(), 0);
}

// Two cameras facing each other, the knot 2 mm from the line between their centres: their rays
// are 0.15 deg from head-on and place it anywhere along that line; the other cameras are not
// told to look for it there.
TEST(MissingKnots, TwoFacingCamerasAloneDoNotPlaceAKnotOnTheLineBetweenThem) {
  calib::Rig rig;
  rig.cameras = {calib::LookAtCamera("a", {-1.5, 0.0, 0.0}, {0, 0, 0}, 16.0, 5.5, 1024),
                 calib::LookAtCamera("facing", {1.5, 0.0, 0.0}, {0, 0, 0}, 16.0, 5.5, 1024),
                 calib::LookAtCamera("b", {-1.4, 0.55, 0.1}, {0, 0, 0}, 16.0, 5.5, 1024)};
  const Eigen::Vector3d knot(0.0, 0.002, 0.0);
  recon::LabelSet labels = recon::LabelSet::Empty(1, 1, {"a", "facing", "b"}, {0});
  // Labeled 0.3 px off the truth in each facing camera, as a person would.
  labels.at(0, 0, 0) = Scene::Accepted(rig.cameras[0].ProjectWorld(knot) + Eigen::Vector2d(0.3, 0));
  labels.at(1, 0, 0) = Scene::Accepted(rig.cameras[1].ProjectWorld(knot) + Eigen::Vector2d(0, 0.3));
  // The pair triangulates, valid and within the residual tolerance: only its geometry says it
  // is no point.
  std::vector<recon::Observation> views = {{0, labels.at(0, 0, 0).px}, {1, labels.at(1, 0, 0).px}};
  const recon::PointEstimate e = recon::TriangulatePoint(rig, views);
  const MissingKnotsOptions defaults;
  ASSERT_TRUE(e.valid) << e.why;
  for (double r : e.residual_px) EXPECT_LT(r, defaults.max_residual_px);
  EXPECT_GT(recon::LargestSigmaM(e), 4 * recon::kMaxUnitSigmaM);
  EXPECT_FALSE(recon::UsableGeometry(e));
  LabelDocument doc(labels, "/nonexistent/labels.h5");
  const MissingKnots missing(&doc, &rig, {0, 1, 2});
  EXPECT_EQ(missing.Find(2, 0, 0), nullptr);
  // Without the check, b would be sent to look for it far from where it is.
  MissingKnotsOptions unchecked;
  unchecked.max_unit_sigma_mm = 1e9;
  const MissingKnots misled(&doc, &rig, {0, 1, 2}, unchecked);
  const MissingKnot* wrong = misled.Find(2, 0, 0);
  ASSERT_NE(wrong, nullptr);
  EXPECT_GT((wrong->expected_px - rig.cameras[2].ProjectWorld(knot)).norm(), 5.0);
  // a and b (rays 20 deg apart) place it: the facing camera is told where it is.
  labels.at(1, 0, 0) = recon::Label{};
  labels.at(2, 0, 0) = Scene::Accepted(rig.cameras[2].ProjectWorld(knot));
  LabelDocument usable(labels, "/nonexistent/labels.h5");
  const MissingKnots listed(&usable, &rig, {0, 1, 2});
  const MissingKnot* m = listed.Find(1, 0, 0);
  ASSERT_NE(m, nullptr);
  EXPECT_EQ(m->basis, recon::MissingBasis::kCameras);
  EXPECT_LT((m->expected_px - rig.cameras[1].ProjectWorld(knot)).norm(), 1.0);
}

// The target (a box between camera c and the centre knot) hides that knot from c: not missing
// there, though a and b place it; still missing in the edge camera, which sees past the box.
TEST(MissingKnots, AKnotTheTargetHidesIsNotMissing) {
  const Scene scene;
  recon::LabelSet labels = scene.Labels();
  labels.at(2, 1, 4) = recon::Label{};  // c has nothing of the centre knot in row 1
  const Eigen::Vector3d c_centre = scene.rig.cameras[2].Center();
  // A 4 cm box halfway along c's line of sight at frame 1 (time 1 / 100 s), moving 1 m/s along y:
  // at frame 3 it is 2 cm further, beside the line.
  recon::Target target;
  target.fps = 100.0;
  recon::TargetSolid box;
  box.velocity = Eigen::Vector3d(0.0, 1.0, 0.0);
  box.center = 0.5 * (c_centre + scene.knots[1][4]) - 0.01 * box.velocity;
  box.half_extents = Eigen::Vector3d::Constant(0.02);
  target.solids = {box};
  EXPECT_TRUE(recon::TargetHides(target, c_centre, scene.knots[1][4], 0.01));
  EXPECT_FALSE(recon::TargetHides(target, c_centre, scene.knots[1][4], 0.06));  // moved on
  EXPECT_FALSE(recon::TargetHides(target, scene.rig.cameras[0].Center(), scene.knots[1][4], 0.01));
  EXPECT_TRUE(recon::TargetHides(target, c_centre, scene.knots[1][4], 0.03, 0.02));  // grown
  MissingKnotsOptions options;
  options.target = target;
  LabelDocument doc(labels, "/nonexistent/labels.h5");
  const MissingKnots with_target(&doc, &scene.rig, kRigIndex, options);
  const MissingKnots without(&doc, &scene.rig, kRigIndex);
  EXPECT_NE(without.Find(2, 1, 4), nullptr);
  EXPECT_EQ(with_target.Find(2, 1, 4), nullptr);
  EXPECT_EQ(with_target.Items().size(), without.Items().size() - 1);
  // A ball hides as well.
  recon::TargetSolid ball;
  ball.shape = recon::TargetSolid::Shape::kSphere;
  ball.center = 0.5 * (c_centre + scene.knots[1][4]);
  ball.radius = 0.01;
  options.target.solids = {ball};
  const MissingKnots with_ball(&doc, &scene.rig, kRigIndex, options);
  EXPECT_EQ(with_ball.Find(2, 1, 4), nullptr);
  EXPECT_EQ(with_ball.Items().size(), without.Items().size() - 1);
}

// The target of a project: the scenario's box (Net A's satellite mock-up, 0.4 x 0.3 x 0.3 m at
// x = 2.2 m), named by the project file relative to its folder; a file without a box or a ball,
// or none at all, refused by name.
TEST(MissingKnots, TheTargetIsTheScenariosBodyTheProjectNames) {
  const std::string scenario = std::string(NETLAB_SOURCE_DIR) + "/scenarios/net_a_0.5.yaml";
  const recon::Target target = LoadTarget(scenario, 179.0);
  ASSERT_EQ(target.solids.size(), 1u);
  EXPECT_EQ(target.solids[0].shape, recon::TargetSolid::Shape::kBox);
  EXPECT_LT((target.solids[0].center - Eigen::Vector3d(2.2, 0, 0)).norm(), 1e-12);
  EXPECT_LT((target.solids[0].half_extents - Eigen::Vector3d(0.2, 0.15, 0.15)).norm(), 1e-12);
  EXPECT_EQ(target.fps, 179.0);
  for (const std::string& bad : {std::string(NETLAB_SOURCE_DIR) + "/scenarios/pendulum.yaml",
                                 std::string("/nonexistent/sim.h5")}) {
    try {
      LoadTarget(bad, 179.0);
      ADD_FAILURE() << "took " << bad;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(bad), std::string::npos) << e.what();
    }
  }
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / "netlab_missing_knots_project";
  std::filesystem::create_directories(dir);
  Project p;
  p.experiment = (dir / "shot/experiment.yaml").string();
  p.rig = (dir / "shot/rig_true.yaml").string();
  p.labels = (dir / "labels.h5").string();
  p.target = (dir / "sim.h5").string();
  p.rows = p.cols = 11;
  const std::string path = (dir / "project.yaml").string();
  SaveProject(p, path);
  EXPECT_EQ(LoadProject(path).target, p.target);
  p.target.clear();
  SaveProject(p, path);
  EXPECT_EQ(LoadProject(path).target, "");
  std::filesystem::remove_all(dir);
}

TEST(MissingKnots, WithTheNeighbourRuleAKnotAmongUnlabeledNeighboursWaits) {
  const Scene scene;
  recon::LabelSet labels = scene.Labels();
  labels.at(2, 1, 4) = recon::Label{};
  LabelDocument doc(labels, "/nonexistent/labels.h5");
  MissingKnotsOptions options;
  options.need_labeled_neighbour = true;
  const MissingKnots missing(&doc, &scene.rig, kRigIndex, options);
  // c's knot 4 has its four neighbours labeled in c; the edge camera has no label at all.
  EXPECT_EQ(missing.Items(), (std::vector<LabelKey>{{2, 1, 4}}));
  // One of the edge camera's knots labeled: its neighbours in the picture are listed.
  const int k = EdgeItems(scene, 0).front().knot;
  doc.Apply("Place", {{3, 0, k, Scene::Accepted(scene.Truth(3, 0, k))}});
  std::set<int> listed;
  for (const auto& [c, t, knot] : missing.Items())
    if (c == 3) listed.insert(knot);
  std::set<int> want;
  for (int n : recon::GridSlots(kRows, kCols, k))
    if (n >= 0 && scene.InPicture(3, 0, n)) want.insert(n);
  ASSERT_FALSE(want.empty());
  EXPECT_EQ(listed, want);
}

TEST(MissingKnots, RunFromGivesTheFollowingFramesItIsMissingIn) {
  const Scene scene;
  recon::LabelSet labels = scene.Labels();
  for (int t : {1, 2, 3}) labels.at(2, t, 4) = recon::Label{};
  LabelDocument doc(labels, "/nonexistent/labels.h5");
  const MissingKnots missing(&doc, &scene.rig, kRigIndex);
  EXPECT_EQ(missing.RunFrom(2, 1, 4), (std::vector<int>{1, 2, 3}));
  EXPECT_EQ(missing.RunFrom(2, 0, 4), (std::vector<int>{}));
  doc.Apply("Mark hidden", {{2, 2, 4, recon::Label::Hidden()}});
  EXPECT_EQ(missing.RunFrom(2, 1, 4), (std::vector<int>{1}));
  EXPECT_EQ(missing.RunFrom(2, 3, 4), (std::vector<int>{3}));
}

TEST(MissingKnots, InvalidOptionsAreRefusedByName) {
  const Scene scene;
  LabelDocument doc(scene.Labels(), "/nonexistent/labels.h5");
  MissingKnotsOptions options;
  options.max_residual_px = 0.0;
  try {
    MissingKnots missing(&doc, &scene.rig, kRigIndex, options);
    FAIL() << "accepted max_residual_px = 0";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("max_residual_px"), std::string::npos) << e.what();
  }
  std::string why;
  options = {};
  options.label_sigma_px = -0.1;
  EXPECT_FALSE(options.IsValid(&why));
  EXPECT_NE(why.find("label_sigma_px"), std::string::npos) << why;
  options = {};
  options.edge_sigmas = std::nan("");
  EXPECT_FALSE(options.IsValid(&why));
  EXPECT_NE(why.find("edge_sigmas"), std::string::npos) << why;
}

}  // namespace
}  // namespace netlab::gui
