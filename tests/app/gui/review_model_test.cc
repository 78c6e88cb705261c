// The review queue's model under QAbstractItemModelTester while labels come and go, with and
// without missing knots, and its walk order (Space / Shift+Space in the window).

#include "app/gui/document/review_model.h"

#include <gtest/gtest.h>

#include <QAbstractItemModelTester>
#include <QCoreApplication>
#include <QSignalSpy>
#include <QSortFilterProxyModel>

#include "app/gui/document/missing_knots.h"

namespace netlab::gui {
namespace {

recon::Label Review(double x, float confidence) {
  recon::Label l;
  l.px = {x, 1};
  l.source = recon::LabelSource::kTracked;
  l.confidence = confidence;
  l.state = recon::LabelState::kNeedsReview;
  return l;
}

TEST(ReviewModel, PassesTheModelTesterWhileLabelsChange) {
  LabelDocument doc(recon::LabelSet::Empty(2, 3, {"cam0", "cam1", "cam2"}, {5, 6, 7, 8}),
                    "/nonexistent/labels.h5");
  ReviewModel model(&doc, {5, 6, 7, 8});
  QAbstractItemModelTester tester(&model, QAbstractItemModelTester::FailureReportingMode::Fatal);
  QSortFilterProxyModel proxy;
  proxy.setSourceModel(&model);
  proxy.setSortRole(Qt::EditRole);
  QAbstractItemModelTester proxy_tester(&proxy,
                                        QAbstractItemModelTester::FailureReportingMode::Fatal);
  EXPECT_EQ(model.rowCount(), 0);
  doc.Apply("Track", {{2, 3, 5, Review(1, 0.2f)}, {0, 1, 0, Review(2, 0.9f)}});
  doc.MergeReasons({{{2, 3, 5}, "moved 2.1 px otherwise than its neighbours"}});
  ASSERT_EQ(model.rowCount(), 2);
  EXPECT_EQ(model.columnCount(), ReviewModel::kColumns);
  // Frame order: frame row 1 (frame 6) first.
  EXPECT_EQ(model.index(0, ReviewModel::kFrame).data().toInt(), 6);
  EXPECT_EQ(model.index(1, ReviewModel::kCamera).data().toString(), "cam2");
  EXPECT_EQ(model.index(1, ReviewModel::kKnot).data().toString(), "(1, 2)");
  EXPECT_EQ(model.index(1, ReviewModel::kReason).data().toString(),
            "moved 2.1 px otherwise than its neighbours");
  EXPECT_EQ(model.index(1, ReviewModel::kSource).data().toString(), "tracked");
  EXPECT_NEAR(model.index(1, ReviewModel::kSeverity).data(Qt::EditRole).toDouble(), 0.8, 1e-6);
  // Sorted by severity, most doubtful first.
  proxy.sort(ReviewModel::kSeverity, Qt::DescendingOrder);
  EXPECT_EQ(proxy.index(0, ReviewModel::kCamera).data().toString(), "cam2");
  doc.Apply("Accept", {{2, 3, 5, recon::Label{}}});
  EXPECT_EQ(model.rowCount(), 1);
  doc.undo_stack()->undo();
  EXPECT_EQ(model.rowCount(), 2);
}

TEST(ReviewModel, NextAndPreviousWalkTheQueueInOrderAndWrap) {
  LabelDocument doc(recon::LabelSet::Empty(2, 2, {"a", "b"}, {0, 1, 2}), "/nonexistent/l.h5");
  ReviewModel model(&doc, {0, 1, 2});
  EXPECT_EQ(model.Next({0, 0, 0}), -1);  // empty
  doc.Apply("Track",
            {{1, 0, 3, Review(1, 0.5f)}, {0, 2, 1, Review(1, 0.5f)}, {0, 0, 2, Review(1, 0.5f)}});
  // Queue: (frame 0, a, 2), (frame 0, b, 3), (frame 2, a, 1).
  LabelKey at{0, 0, 0};
  std::vector<LabelKey> walked;
  for (int i = 0; i < 4; ++i) {
    at = model.items()[model.Next(at)];
    walked.push_back(at);
  }
  EXPECT_EQ(walked, (std::vector<LabelKey>{{0, 0, 2}, {1, 0, 3}, {0, 2, 1}, {0, 0, 2}}));
  EXPECT_EQ(model.items()[model.Previous({0, 0, 2})], (LabelKey{0, 2, 1}));
  EXPECT_EQ(model.items()[model.Previous({0, 2, 1})], (LabelKey{1, 0, 3}));
}

// The Severity column follows the reason when it says more than the detector's confidence: a
// label flagged 1555.8 px off is 1.00 however sure its junction was; a small distance leaves
// the confidence's word; the cameras disagreeing is 1.
TEST(ReviewModel, SeverityFollowsTheReasonsDistance) {
  LabelDocument doc(recon::LabelSet::Empty(2, 2, {"a", "b"}, {0, 1}), "/nonexistent/l.h5");
  ReviewModel model(&doc, {0, 1});
  doc.Apply("Track", {{0, 0, 0, Review(1, 0.95f)},
                      {0, 0, 1, Review(2, 0.95f)},
                      {0, 0, 2, Review(3, 0.95f)},
                      {0, 0, 3, Review(4, 0.6f)}});
  doc.MergeReasons({{{0, 0, 0}, "epipolar check: 1555.8 px off the point of all the cameras"},
                    {{0, 0, 1}, "epipolar check: 4.0 px from where the other cameras put the knot"},
                    {{0, 0, 2}, "epipolar check: the cameras disagree (rays 0.00 deg apart)"},
                    {{0, 0, 3}, "moved 0.5 px otherwise than its neighbours"}});
  ASSERT_EQ(model.rowCount(), 4);
  const auto severity = [&](int row) {
    return model.index(row, ReviewModel::kSeverity).data(Qt::EditRole).toDouble();
  };
  EXPECT_DOUBLE_EQ(severity(0), 1.0);
  EXPECT_EQ(model.index(0, ReviewModel::kSeverity).data().toString(), "1.00");
  EXPECT_NEAR(severity(1), 4.0 / kSurePx, 1e-9);
  EXPECT_DOUBLE_EQ(severity(2), 1.0);
  EXPECT_NEAR(severity(3), 0.4, 1e-6);  // 1 - confidence: more than 0.5 px says
  EXPECT_DOUBLE_EQ(ReasonSeverity("kept for review (no reason recorded)"), 0.0);
}

// The engine gives its reasons after the edits it applied: the rows' reason and severity are
// announced anew (a view showed the reason of before), and only when a reason changed.
TEST(ReviewModel, AReasonGivenAfterItsEditReachesTheView) {
  LabelDocument doc(recon::LabelSet::Empty(2, 2, {"a", "b"}, {0, 1}), "/nonexistent/l.h5");
  ReviewModel model(&doc, {0, 1});
  QAbstractItemModelTester tester(&model, QAbstractItemModelTester::FailureReportingMode::Fatal);
  doc.Apply("Find Node", {{1, 1, 2, Review(1, 0.9f)}});
  ASSERT_EQ(model.rowCount(), 1);
  QSignalSpy changed(&model, &QAbstractItemModel::dataChanged);
  doc.MergeReasons({{{1, 1, 2}, "12.0 px from where the other cameras' labels put the knot"}});
  ASSERT_EQ(changed.count(), 1);
  const auto from = changed[0][0].value<QModelIndex>(), to = changed[0][1].value<QModelIndex>();
  EXPECT_LE(from.column(), ReviewModel::kSeverity);
  EXPECT_GE(to.column(), ReviewModel::kReason);
  EXPECT_EQ(to.row(), 0);
  EXPECT_EQ(model.index(0, ReviewModel::kSeverity).data().toString(), "1.00");
  doc.MergeReasons({{{1, 1, 2}, "12.0 px from where the other cameras' labels put the knot"}});
  EXPECT_EQ(changed.count(), 1);  // nothing new
}

// Both kinds in one queue: a 2 x 2 net 1.5 m before three cameras, labeled exactly in a and b;
// camera c has a doubtful label of knot 1 in frame row 0 and nothing else. Its other knots are
// missing there (a and b agree on them); the model lists both kinds in the queue's order, says
// "missing" in the source column, sorts them with the rest and follows every edit, under the
// model tester.
TEST(ReviewModel, ListsMissingKnotsWithTheLabelsUnderReview) {
  calib::Rig rig;
  rig.cameras = {calib::LookAtCamera("a", {-1.5, 0.0, 0.0}, {0, 0, 0}, 16.0, 5.5, 1024),
                 calib::LookAtCamera("b", {-1.4, 0.55, 0.1}, {0, 0, 0}, 16.0, 5.5, 1024),
                 calib::LookAtCamera("c", {-1.35, -0.45, -0.3}, {0, 0, 0}, 16.0, 5.5, 1024)};
  auto truth = [&](int c, int k) {
    return rig.cameras[c].ProjectWorld(Eigen::Vector3d(0.0, (k % 2) * 0.1, (k / 2) * 0.1));
  };
  recon::LabelSet labels = recon::LabelSet::Empty(2, 2, {"a", "b", "c"}, {7});
  for (int c = 0; c < 2; ++c)
    for (int k = 0; k < 4; ++k) {
      labels.at(c, 0, k) = Review(0, 1.0f);
      labels.at(c, 0, k).px = truth(c, k);
      labels.at(c, 0, k).state = recon::LabelState::kAccepted;
    }
  labels.at(2, 0, 1) = Review(0, 0.7f);
  labels.at(2, 0, 1).px = truth(2, 1) + Eigen::Vector2d(3, 0);
  LabelDocument doc(labels, "/nonexistent/labels.h5");
  const MissingKnots missing(&doc, &rig, {0, 1, 2});
  ReviewModel model(&doc, {7});
  QAbstractItemModelTester tester(&model, QAbstractItemModelTester::FailureReportingMode::Fatal);
  QSortFilterProxyModel proxy;
  proxy.setSourceModel(&model);
  proxy.setSortRole(Qt::EditRole);
  QAbstractItemModelTester proxy_tester(&proxy,
                                        QAbstractItemModelTester::FailureReportingMode::Fatal);
  EXPECT_EQ(model.rowCount(), 1);  // review items only until SetMissing
  model.SetMissing(&missing);
  // c: knot 0 missing, 1 under review, 2 and 3 missing.
  ASSERT_EQ(model.items(), (std::vector<LabelKey>{{2, 0, 0}, {2, 0, 1}, {2, 0, 2}, {2, 0, 3}}));
  EXPECT_TRUE(model.IsMissing(0));
  EXPECT_FALSE(model.IsMissing(1));
  EXPECT_EQ(model.index(0, ReviewModel::kSource).data().toString(), "missing");
  EXPECT_EQ(model.index(1, ReviewModel::kSource).data().toString(), "tracked");
  EXPECT_TRUE(model.index(2, 0).data(ReviewModel::kMissingRole).toBool());
  EXPECT_TRUE(model.index(2, ReviewModel::kReason)
                  .data()
                  .toString()
                  .startsWith("no label; seen in a, b; expected near ("));
  EXPECT_EQ(model.index(2, ReviewModel::kReason).data(Qt::ToolTipRole),
            model.index(2, ReviewModel::kReason).data());
  EXPECT_DOUBLE_EQ(model.index(0, ReviewModel::kSeverity).data(Qt::EditRole).toDouble(), 1.0);
  // Sorted by source: "missing" rows before "tracked".
  proxy.sort(ReviewModel::kSource, Qt::AscendingOrder);
  EXPECT_EQ(proxy.index(0, ReviewModel::kSource).data().toString(), "missing");
  EXPECT_EQ(proxy.index(3, ReviewModel::kSource).data().toString(), "tracked");
  // The walk takes both kinds in the queue's order.
  EXPECT_EQ(model.Next({2, 0, 0}), 1);
  EXPECT_EQ(model.Next({2, 0, 1}), 2);
  EXPECT_EQ(model.Previous({2, 0, 0}), 3);
  // Labeled, marked hidden: off the queue; the doubtful label accepted: off too.
  recon::Label placed = labels.at(0, 0, 0);
  placed.px = truth(2, 0);
  doc.Apply("Find Node", {{2, 0, 0, placed}});
  doc.Apply("Mark hidden", {{2, 0, 3, recon::Label::Hidden()}});
  EXPECT_EQ(model.items(), (std::vector<LabelKey>{{2, 0, 1}, {2, 0, 2}}));
  doc.Apply("Accept", {{2, 0, 1, placed}});
  EXPECT_EQ(model.items(), (std::vector<LabelKey>{{2, 0, 2}}));
  doc.undo_stack()->undo();
  doc.undo_stack()->undo();
  EXPECT_EQ(model.rowCount(), 3);
  model.SetMissing(nullptr);
  EXPECT_EQ(model.items(), (std::vector<LabelKey>{{2, 0, 1}}));
}

}  // namespace
}  // namespace netlab::gui
