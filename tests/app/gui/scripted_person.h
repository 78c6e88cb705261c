#pragma once
// A scripted person at the workstation, with real mouse, wheel and key events (shared by the
// window's test and bench_gui): seeds the four corners of frame 0 in every camera (a Find Node
// click each, zoomed in; a Shift+click where Find Node finds none or several), runs Find Path
// from the corners (Ctrl+P), clicks every visible knot of frame 0 still without an accepted label
// (as the corners), tracks (T: a run stops at the first frame with a label for review), fixes that
// frame's items in the review queue (FixReviewItem; the window moves on to the next by itself),
// tracks on, and so on to the last frame with nothing left in the queue. A missing knot (no label
// where the other cameras see it) is labeled like a review item, or marked hidden where the truth
// has none: in every following frame it is missing in (Shift+D) when the truth has none there
// either, else here (D).

#include <Eigen/Core>
#include <QCoreApplication>
#include <QSortFilterProxyModel>
#include <QTableView>
#include <QTest>
#include <QWheelEvent>
#include <algorithm>
#include <tuple>
#include <vector>

#include "app/gui/camera_view.h"
#include "app/gui/main_window.h"
#include "libreconstruct/labels/label_set.h"

namespace netlab::gui {

// One action of the person, to replay on the engine without a window.
struct Action {
  enum Kind { kFindNode, kPlace, kDelete, kAccept, kFindPath, kTrack, kHide, kHideRun } kind;
  static constexpr int kKinds = kHideRun + 1;  // how many kinds there are
  int camera = 0, t = 0, knot = 0;
  Eigen::Vector2d px = Eigen::Vector2d::Zero();
};

// Clicks (with `modifiers`) the view at image pixel px; returns the image pixel the click lands
// on (the widget point is whole pixels).
inline Eigen::Vector2d ClickAt(CameraView* view, const Eigen::Vector2d& px,
                               Qt::KeyboardModifiers modifiers = {}) {
  const QPoint point = view->ToWidget(px).toPoint();
  const Eigen::Vector2d at = view->ToImage(QPointF(point));  // before: the click may re-zoom it
  QTest::mouseMove(view, point);
  QTest::mouseClick(view, Qt::LeftButton, modifiers, point);
  return at;
}

// Zooms the view in at image pixel px with wheel events (as a person does before a click).
inline void ZoomAt(CameraView* view, const Eigen::Vector2d& px, int notches) {
  for (int i = 0; i < notches; ++i) {
    const QPointF at = view->ToWidget(px);
    QWheelEvent wheel(at, view->mapToGlobal(at), QPoint(), QPoint(0, 120), Qt::NoButton,
                      Qt::NoModifier, Qt::NoScrollPhase, false);
    QCoreApplication::sendEvent(view, &wheel);
  }
}

// Moves the knot picker to `knot` with the '.' and ',' keys.
inline void PickKnot(MainWindow* w, int knot) {
  while (w->knot() < knot) QTest::keyClick(w, Qt::Key_Period);
  while (w->knot() > knot) QTest::keyClick(w, Qt::Key_Comma);
}

struct ScriptedSession {
  std::vector<Action> actions;  // what the person did that changes labels, and the tracking runs
  bool finished = false;        // every tracking run ended
  int review_items = 0;         // review items the person fixed
  int navigation = 0;           // keys that only went to an item (Ctrl+Home, Space)
};

// Tracks forwards from the current frame (T) and waits for the run; false when it did not end.
inline bool TrackForwards(MainWindow* w, ScriptedSession* out) {
  const int from = w->frame();
  QTest::keyClick(w, Qt::Key_T);
  const bool ended = QTest::qWaitFor([&] { return !w->busy(); }, 600000);
  out->actions.push_back({Action::kTrack, 0, from, 0, Eigen::Vector2d::Zero()});
  return ended;
}

// Fixes the queue's item the window shows (its camera, frame and knot: a label for review or a
// missing knot), whose true label is `truth`: where the knot is hidden, a label deleted (D), a
// missing knot marked hidden (D; Shift+D when the truth has it hidden in every following frame
// it is missing in); a label within 1 px of the truth accepted (A); anything else fixed with a
// Find Node click at the true place (and a Shift+click if that stays in doubt). Returns whether
// it left a label (which tracking on from here carries forwards).
inline bool FixReviewItem(MainWindow* w, const recon::LabelSet& truth_set, ScriptedSession* out) {
  Session* s = w->session();
  const int c = w->camera(), t = w->frame(), k = w->knot();
  auto want = [&](int u) -> const recon::Label& {
    return truth_set.at(truth_set.FindCamera(s->camera_names()[c]), u, k);
  };
  const recon::Label& truth = want(t);
  if (!truth.present()) {
    const bool labeled = s->document().at(c, t, k).present();
    bool run_hidden = !labeled;  // hidden in every frame it is missing in from here
    for (int u : s->missing().RunFrom(c, t, k)) run_hidden = run_hidden && !want(u).present();
    if (run_hidden) {
      QTest::keyClick(w, Qt::Key_D, Qt::ShiftModifier);
      out->actions.push_back({Action::kHideRun, c, t, k, Eigen::Vector2d::Zero()});
    } else {
      QTest::keyClick(w, Qt::Key_D);  // a label deleted; a missing knot marked hidden
      out->actions.push_back(
          {labeled ? Action::kDelete : Action::kHide, c, t, k, Eigen::Vector2d::Zero()});
    }
    return false;
  }
  if ((s->document().at(c, t, k).px - truth.px).norm() < 1.0) {
    QTest::keyClick(w, Qt::Key_A);
    out->actions.push_back({Action::kAccept, c, t, k, Eigen::Vector2d::Zero()});
    return true;
  }
  out->actions.push_back({Action::kFindNode, c, t, k, ClickAt(w->view(c), truth.px)});
  if (s->document().at(c, t, k).state != recon::LabelState::kAccepted)
    out->actions.push_back(
        {Action::kPlace, c, t, k, ClickAt(w->view(c), truth.px, Qt::ShiftModifier)});
  return true;
}

// Plays the session on an open window whose recording `truth` (labels_true.h5) describes.
inline ScriptedSession PlayScriptedSession(MainWindow* w, const recon::LabelSet& truth,
                                           int max_review_items = 400) {
  ScriptedSession out;
  Session* s = w->session();
  const int rows = s->project().rows, cols = s->project().cols;
  auto want = [&](int c, int t, int k) -> const recon::Label& {
    return truth.at(truth.FindCamera(s->camera_names()[c]), t, k);
  };
  // 1. The four corners of frame 0 in every camera that sees them.
  for (int c = 0; c < s->cameras(); ++c)
    for (int k : {0, cols - 1, (rows - 1) * cols, rows * cols - 1}) {
      if (!want(c, 0, k).present()) continue;
      PickKnot(w, k);
      ZoomAt(w->view(c), want(c, 0, k).px, 8);
      out.actions.push_back({Action::kFindNode, c, 0, k, ClickAt(w->view(c), want(c, 0, k).px)});
      if (!s->document().at(c, 0, k).present())  // none or several: exactly here
        out.actions.push_back(
            {Action::kPlace, c, 0, k, ClickAt(w->view(c), want(c, 0, k).px, Qt::ShiftModifier)});
      QTest::keyClick(w, Qt::Key_F, Qt::ControlModifier);  // fit again
    }
  // 2. Find Path from the corners; then every visible knot of frame 0 that is not accepted in a
  // camera, clicked there (Find Node, zoomed in; Shift+click where it cannot decide).
  // Ctrl+P previews on a worker; Enter applies it.
  QTest::keyClick(w, Qt::Key_P, Qt::ControlModifier);
  w->WaitForIdle(120000);
  if (w->fill_grid_preview()) QTest::keyClick(w, Qt::Key_Return);
  out.actions.push_back({Action::kFindPath, 0, 0, 0, Eigen::Vector2d::Zero()});
  for (int c = 0; c < s->cameras(); ++c)
    for (int k = 0; k < rows * cols; ++k) {
      const recon::Label& l = s->document().at(c, 0, k);
      if (!want(c, 0, k).present() || l.accepted()) continue;
      PickKnot(w, k);
      ZoomAt(w->view(c), want(c, 0, k).px, 8);
      out.actions.push_back({Action::kFindNode, c, 0, k, ClickAt(w->view(c), want(c, 0, k).px)});
      if (s->document().at(c, 0, k).state != recon::LabelState::kAccepted)
        out.actions.push_back(
            {Action::kPlace, c, 0, k, ClickAt(w->view(c), want(c, 0, k).px, Qt::ShiftModifier)});
      QTest::keyClick(w, Qt::Key_F, Qt::ControlModifier);
    }
  // 3. Tracking and the review queue, a frame at a time (docs/gui.md, the workflow). A run stops
  // at the first frame with a label for review and shows its first item; after each fix the
  // window goes on to the frame's next item by itself. The person fixes the frame's labels for
  // review, then tracks on from there (T), which carries the labels forwards and replaces what a
  // run carried from a label in doubt. Missing knots wait until the runs reach the last frame:
  // the target hides the same knots for many frames, and Shift+D then marks a whole run of them
  // hidden at once. Then the queue is walked from its first item (Ctrl+Home; Space when the
  // window did not move on); a fixed label for review is tracked on from.
  const int last = s->frames() - 1;
  // The queue in the order Space and Ctrl+Home walk it: the window's ReviewModel (the source of
  // its review table's sorting proxy).
  const auto* proxy = qobject_cast<const QSortFilterProxyModel*>(w->review_table()->model());
  const auto* queue = proxy ? qobject_cast<const ReviewModel*>(proxy->sourceModel()) : nullptr;
  if (!queue) return out;
  auto review_label = [&](int c, int t, int k) {
    const recon::Label& l = s->document().at(c, t, k);
    return l.present() && l.state == recon::LabelState::kNeedsReview;
  };
  auto on_item = [&] {
    const int c = w->camera(), t = w->frame(), k = w->knot();
    return review_label(c, t, k) || s->missing().Find(c, t, k) != nullptr;
  };
  auto labels_for_review_in = [&](int t) {
    for (const auto& [c, u, k] : queue->items())
      if (u == t && review_label(c, u, k)) return true;
    return false;
  };
  bool track_on = true;
  out.finished = true;
  while (out.finished && out.review_items < max_review_items) {
    if (track_on) {
      out.finished = TrackForwards(w, &out);
      if (!out.finished) break;
    }
    const int round = w->frame();
    if (round != last && labels_for_review_in(round)) {
      // A run that stopped: this frame's labels for review (missing knots left for later).
      for (int guard = 0; labels_for_review_in(round) && out.review_items < max_review_items &&
                          guard <= static_cast<int>(queue->items().size());) {
        if (!review_label(w->camera(), w->frame(), w->knot())) {
          QTest::keyClick(w, Qt::Key_Space);
          ++out.navigation;
          ++guard;
          continue;
        }
        ++out.review_items;
        FixReviewItem(w, truth, &out);
      }
      track_on = true;
      continue;
    }
    // The runs reached the last frame: the queue from its first item.
    if (queue->items().empty()) break;
    if (!on_item()) {
      QTest::keyClick(w, Qt::Key_Home, Qt::ControlModifier);
      ++out.navigation;
    }
    ++out.review_items;
    track_on = FixReviewItem(w, truth, &out) && w->frame() != last;
  }
  return out;
}

}  // namespace netlab::gui
