// The review queue's missing knots without a window (app/gui/document/missing_knots.h): a 3 x 3
// net 1.5 m in front of three cameras that label it exactly, a fourth that sees part of it and a
// fifth that looks away. Listed where two other cameras put the knot, never from one camera or a
// disagreeing pair, off the list once labeled or marked hidden, back on undo; the incremental
// count always equals a count from scratch.

#include "app/gui/document/missing_knots.h"

#include <gtest/gtest.h>

#include <QCoreApplication>
#include <QSignalSpy>
#include <cstdio>
#include <set>
#include <string>
#include <vector>

namespace netlab::gui {
namespace {

constexpr int kRows = 3, kCols = 3, kKnots = kRows * kCols, kFrames = 4;
constexpr double kMargin = 20.0;  // MissingKnotsOptions::margin_px's default

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
  Eigen::Vector2d Truth(int c, int t, int k) const { return rig.cameras[c].ProjectWorld(knots[t][k]); }
  bool InsideByMargin(int c, int t, int k) const {
    const Eigen::Vector2d q = Truth(c, t, k);
    return q.allFinite() && q.minCoeff() >= kMargin && q.maxCoeff() <= 1023 - kMargin;
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
    if (scene.InsideByMargin(3, t, k)) items.emplace_back(3, t, k);
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

TEST(MissingKnots, ALabelOrAHiddenMarkTakesItOffTheListAndUndoPutsItBack) {
  const Scene scene;
  recon::LabelSet labels = scene.Labels();
  labels.at(2, 1, 4) = recon::Label{};
  LabelDocument doc(labels, "/nonexistent/labels.h5");
  const MissingKnots missing(&doc, &scene.rig, kRigIndex);
  QSignalSpy changed(&missing, &MissingKnots::changed);
  ASSERT_NE(missing.Find(2, 1, 4), nullptr);
  // Labeled (where the other cameras put it): off the list; only row 1 counted again.
  doc.Apply("Find Node", {{2, 1, 4, Scene::Accepted(scene.Truth(2, 1, 4))}});
  EXPECT_EQ(missing.Find(2, 1, 4), nullptr);
  ASSERT_EQ(changed.count(), 1);
  EXPECT_EQ(changed.last().at(0).value<QList<int>>(), QList<int>({1}));
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

TEST(MissingKnots, OneOtherCameraOrADisagreeingPairSaysNothing) {
  const Scene scene;
  recon::LabelSet labels = scene.Labels();
  // Knot 4 of row 0 seen by camera a alone: nothing expected in b, c or edge.
  labels.at(1, 0, 4) = labels.at(2, 0, 4) = recon::Label{};
  // Knot 3 of row 2: c lost it, and b's label is 8 px off a's epipolar line (b's image y; the
  // pair's baseline runs along image x).
  labels.at(2, 2, 3) = recon::Label{};
  labels.at(1, 2, 3).px.y() += 8.0;
  // Knot 7 of row 3: a, b, c label it, c 8 px off: the edge camera is not told where it is.
  ASSERT_TRUE(scene.InsideByMargin(3, 3, 7));
  labels.at(2, 3, 7).px.y() += 8.0;
  LabelDocument doc(labels, "/nonexistent/labels.h5");
  const MissingKnots missing(&doc, &scene.rig, kRigIndex);
  for (int c : {1, 2, 3}) EXPECT_EQ(missing.Find(c, 0, 4), nullptr) << "camera " << c;
  EXPECT_EQ(missing.Find(2, 2, 3), nullptr);
  EXPECT_EQ(missing.Find(3, 3, 7), nullptr);
  // The same labels agreeing: each listed.
  recon::LabelSet agreeing = scene.Labels();
  agreeing.at(2, 2, 3) = recon::Label{};
  LabelDocument agreeing_doc(agreeing, "/nonexistent/labels.h5");
  const MissingKnots agreeing_missing(&agreeing_doc, &scene.rig, kRigIndex);
  EXPECT_NE(agreeing_missing.Find(2, 2, 3), nullptr);
  EXPECT_NE(agreeing_missing.Find(3, 3, 7), nullptr);
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
  const int k = std::get<2>(EdgeItems(scene, 0).front());
  doc.Apply("Place", {{3, 0, k, Scene::Accepted(scene.Truth(3, 0, k))}});
  std::set<int> listed;
  for (const auto& [c, t, knot] : missing.Items())
    if (c == 3) listed.insert(knot);
  std::set<int> want;
  for (int n : recon::GridSlots(kRows, kCols, k))
    if (n >= 0 && scene.InsideByMargin(3, 0, n)) want.insert(n);
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
}

}  // namespace
}  // namespace netlab::gui

int main(int argc, char** argv) {
  QCoreApplication app(argc, argv);
  ::testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
