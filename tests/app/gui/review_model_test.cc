// The review queue's model under QAbstractItemModelTester while labels come and go, and its walk
// order (Space / Shift+Space in the window).

#include "app/gui/document/review_model.h"

#include <gtest/gtest.h>

#include <QAbstractItemModelTester>
#include <QCoreApplication>
#include <QSortFilterProxyModel>

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

}  // namespace
}  // namespace netlab::gui

int main(int argc, char** argv) {
  QCoreApplication app(argc, argv);
  ::testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
