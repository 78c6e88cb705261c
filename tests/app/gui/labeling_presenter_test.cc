// The labeling room's rules without a window (app/gui/document/labeling_presenter.h): which item
// of the review queue Space, a fix and a tracking run's stop go to, what a Fill Grid preview's
// ghosts say against the labels, the texts of the preview banner and of a tracking run; the
// cursor's limits (cursor.h); and the helper every background request goes through
// (latest_request.h): only the newest answer arrives, a dropped one never, a cancelled one with
// its flag seen.

#include "app/gui/document/labeling_presenter.h"

#include <gtest/gtest.h>

#include <QCoreApplication>
#include <QElapsedTimer>
#include <atomic>
#include <chrono>
#include <thread>
#include <vector>

#include "app/gui/document/cursor.h"
#include "app/gui/document/latest_request.h"

namespace netlab::gui {
namespace {

recon::Label Review(double x) {
  recon::Label l;
  l.px = {x, 1};
  l.source = recon::LabelSource::kTracked;
  l.confidence = 0.5f;
  l.state = recon::LabelState::kNeedsReview;
  return l;
}

recon::Label Accepted(double x) {
  recon::Label l;
  l.px = {x, 1};
  l.source = recon::LabelSource::kManual;
  l.state = recon::LabelState::kAccepted;
  return l;
}

// Two cameras, three frame rows, a 2 x 2 net; labels for review at (cam, t, knot) =
// (0, 0, 1), (1, 0, 2), (0, 1, 3) and (1, 2, 0).
struct Queue {
  LabelDocument doc{recon::LabelSet::Empty(2, 2, {"a", "b"}, {10, 11, 12}), "/nonexistent/l.h5"};
  ReviewModel model{&doc, {10, 11, 12}};
  ReviewWalk walk{&model, &doc, nullptr};
  Queue() {
    doc.Apply(
        "Track",
        {{0, 0, 1, Review(1)}, {1, 0, 2, Review(2)}, {0, 1, 3, Review(3)}, {1, 2, 0, Review(4)}});
  }
  int Row(const LabelKey& key) const {
    const auto& items = model.items();
    return static_cast<int>(std::find(items.begin(), items.end(), key) - items.begin());
  }
};

TEST(ReviewWalk, AFixAdvancesToTheSameFramesNextLabelOnlyForAnItemTheWindowTookThePersonTo) {
  Queue q;
  // A label fixed on the person's own (no Space before): the window stays.
  q.doc.Apply("Accept", {{0, 0, 1, Accepted(1)}});
  EXPECT_EQ(q.walk.AdvanceRow({0, 0, 1}, true), -1);
  q.doc.undo_stack()->undo();
  // Space took them there: after the fix, the frame's next label for review.
  q.walk.TookTo(q.Row({0, 0, 1}));
  EXPECT_EQ(q.walk.AdvanceRow({0, 0, 1}, true), -1) << "still under review: no advance";
  q.doc.Apply("Accept", {{0, 0, 1, Accepted(1)}});
  const int next = q.walk.AdvanceRow({0, 0, 1}, true);
  ASSERT_GE(next, 0);
  EXPECT_EQ(q.model.items()[next], (LabelKey{1, 0, 2}));
  // A knot that was not in the queue before the fix (a seed) never moves the window.
  EXPECT_EQ(q.walk.AdvanceRow({0, 0, 1}, false), -1);
  // The frame's last item fixed: nothing more in that frame, the window stays (no jump to frame 1).
  q.walk.TookTo(q.Row({1, 0, 2}));
  q.doc.Apply("Delete", {{1, 0, 2, recon::Label{}}});
  EXPECT_EQ(q.walk.AdvanceRow({1, 0, 2}, true), -1);
}

TEST(ReviewWalk, NextWrapsAndATrackingRunsStopShowsTheFramesFirstLabelForReview) {
  Queue q;
  EXPECT_EQ(q.model.items()[q.walk.NextRow({1, 2, 0})], (LabelKey{0, 0, 1}));  // wraps
  EXPECT_EQ(q.model.items()[q.walk.NextRow({0, 0, 1}, true)], (LabelKey{1, 2, 0}));
  EXPECT_EQ(q.model.items()[q.walk.StopRow(1)], (LabelKey{0, 1, 3}));
  EXPECT_EQ(q.walk.StopRow(2), q.Row({1, 2, 0}));
  q.doc.Apply("Accept all", {{0, 0, 1, Accepted(1)},
                             {1, 0, 2, Accepted(2)},
                             {0, 1, 3, Accepted(3)},
                             {1, 2, 0, Accepted(4)}});
  EXPECT_EQ(q.walk.NextRow({0, 0, 0}), -1) << "empty queue";
  EXPECT_EQ(q.walk.StopRow(1), -1);
  EXPECT_TRUE(q.walk.InQueue(0, 0, 1) == false && q.walk.UnderReview(0, 0, 1) == false);
}

TEST(PreviewGhosts, SayNewChangedToReviewAndRemovedAgainstTheLabelsNow) {
  LabelDocument doc(recon::LabelSet::Empty(2, 3, {"a", "b"}, {0, 1}), "/nonexistent/l.h5");
  doc.Apply("Seed", {{0, 0, 1, Accepted(5)}, {0, 0, 2, Accepted(6)}, {0, 0, 3, Review(7)}});
  Session::FillGridPreview p;
  p.t = 0;
  recon::Label moved = Accepted(9);
  p.edits = {{0, 0, 0, Accepted(1)},     // new
             {0, 0, 1, Review(5)},       // the check turns it to review, in place
             {0, 0, 2, recon::Label{}},  // removed
             {0, 0, 3, moved},           // under review, accepted elsewhere: changed
             {1, 0, 4, Accepted(2)}};    // another camera's
  const std::vector<ViewOverlay::Ghost> g = PreviewGhosts(doc, p, 0, 0);
  ASSERT_EQ(g.size(), 4u);
  EXPECT_EQ(g[0].kind, ViewOverlay::Ghost::kNew);
  EXPECT_EQ(g[1].kind, ViewOverlay::Ghost::kToReview);
  EXPECT_TRUE(g[1].review);
  EXPECT_EQ(g[2].kind, ViewOverlay::Ghost::kRemoved);
  EXPECT_EQ(g[2].px, Eigen::Vector2d(6, 1)) << "a removed label's ghost is where it is now";
  EXPECT_EQ(g[3].kind, ViewOverlay::Ghost::kChanged);
  EXPECT_EQ(g[3].from, Eigen::Vector2d(7, 1));
  EXPECT_EQ(g[3].px, Eigen::Vector2d(9, 1));
  EXPECT_TRUE(PreviewGhosts(doc, p, 0, 1).empty()) << "a preview of another frame draws nothing";
}

TEST(PreviewTexts, CountWhatThePreviewChangesAndNameItsKeys) {
  Session::FillGridPreview p;
  p.added = 1;
  p.added_review = 0;
  p.confirmed = 2;
  p.moved = 1;
  EXPECT_EQ(PreviewSummary(p, 40, "Enter", "Esc"),
            "<b>Fill Grid preview, frame 40:</b> 1 new label (0 for review), 2 labels under "
            "review accepted, 1 label moved — dashed pink marks, not labels yet. <b>Enter</b> "
            "accepts (one undo step), <b>Esc</b> discards");
  p.from_corners = true;
  EXPECT_TRUE(
      PreviewSummary(p, 40, "Enter", "Esc").contains("two undo steps: Find Path, Fill Grid"));
  EXPECT_TRUE(
      EmptyPreviewMessage(true, 7).startsWith("Find Path from the corners, frame 7: nothing"));
  Session::TrackRun run;
  run.stopped_for_review = true;
  EXPECT_EQ(TrackMessage(run, 12, 30),
            "Tracked to frame 12: 30 labels (stopped: labels for review in this frame)");
  run.cancelled = true;
  EXPECT_EQ(TrackMessage(run, 12, 30), "Tracked to frame 12: 30 labels (cancelled)");
}

TEST(Cursor, StaysInsideTheProjectAndRemembersThePreviousKnot) {
  Cursor cursor;
  EXPECT_FALSE(cursor.SetFrame(3)) << "no project";
  cursor.Reset(10, 4, 3, 5);
  EXPECT_EQ(cursor.frame(), -1);
  int direction = 7;
  EXPECT_TRUE(cursor.SetFrame(4, &direction));
  EXPECT_EQ(direction, 0) << "from no frame";
  EXPECT_TRUE(cursor.SetFrame(99, &direction));
  EXPECT_EQ(cursor.frame(), 9);
  EXPECT_EQ(direction, 1);
  EXPECT_FALSE(cursor.SetFrame(12)) << "clamped to where it is";
  EXPECT_TRUE(cursor.SetFrame(-5, &direction));
  EXPECT_EQ(cursor.frame(), 0);
  EXPECT_EQ(direction, -1);
  EXPECT_FALSE(cursor.SetCamera(4));
  EXPECT_TRUE(cursor.SetCamera(3));
  EXPECT_EQ(cursor.camera(), 3);
  cursor.SetKnot(7);
  cursor.SetKnot(100);
  EXPECT_EQ(cursor.knot(), 14);
  EXPECT_EQ(cursor.previous_knot(), 7);
  EXPECT_EQ(cursor.KnotName(7), "(1, 2)");
}

// Runs the event loop until `done` or `timeout_ms`.
template <typename Done>
bool Pump(const Done& done, int timeout_ms = 10000) {
  QElapsedTimer timer;
  timer.start();
  while (!done() && timer.elapsed() < timeout_ms)
    QCoreApplication::processEvents(QEventLoop::AllEvents, 5);
  return done();
}

TEST(LatestRequest, OnlyTheNewestAnswerArrives) {
  QObject context;
  std::vector<int> answers;
  LatestRequest<int> request(&context, [&](int v) { answers.push_back(v); });
  std::atomic<bool> release{false};
  request.Request([&](const CancelToken&) {
    while (!release) std::this_thread::sleep_for(std::chrono::milliseconds(1));
    return 1;
  });
  for (int v = 2; v <= 4; ++v) request.Request([v](const CancelToken&) { return v; });
  EXPECT_TRUE(request.pending());
  release = true;
  ASSERT_TRUE(Pump([&] { return !request.pending(); }));
  EXPECT_EQ(answers, std::vector<int>{4}) << "1 was stale, 2 and 3 replaced before they ran";
}

TEST(LatestRequest, ADroppedRequestNeverAnswersAndCancelReachesTheWork) {
  QObject context;
  std::vector<int> answers;
  LatestRequest<int> request(&context, [&](int v) { answers.push_back(v); });
  request.Request([](const CancelToken& cancel) {
    while (!cancel.cancelled()) std::this_thread::sleep_for(std::chrono::milliseconds(1));
    return 5;
  });
  request.Cancel();
  ASSERT_TRUE(Pump([&] { return !answers.empty(); }));
  EXPECT_EQ(answers, std::vector<int>{5}) << "a cancelled run still answers";
  request.Request([](const CancelToken&) { return 6; });
  request.Drop();
  EXPECT_FALSE(request.pending());
  request.Wait();
  Pump([] { return false; }, 200);  // a stray answer would arrive meanwhile
  EXPECT_EQ(answers, std::vector<int>{5});
}

}  // namespace
}  // namespace netlab::gui
