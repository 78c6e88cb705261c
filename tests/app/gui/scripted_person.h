#pragma once
// A scripted person at the workstation, with real mouse, wheel and key events (shared by the
// window's test and bench_gui): seeds the four corners of frame 0 in every camera (a Find Node
// click each, zoomed in; a Shift+click where Find Node finds none or several), runs Find Path
// from the corners (Ctrl+P), clicks every visible knot of frame 0 still without an accepted label
// (as the corners), tracks (T: a run stops at the first frame with a label for review), fixes that
// frame's review items (FixReviewItem; the window moves on to the next by itself), tracks on, and
// so on to the last frame with nothing left for review.

#include <Eigen/Core>
#include <QCoreApplication>
#include <QTest>
#include <QWheelEvent>
#include <vector>

#include "app/gui/camera_view.h"
#include "app/gui/main_window.h"
#include "libreconstruct/labels/label_set.h"

namespace netlab::gui {

// One action of the person, to replay on the engine without a window.
struct Action {
  enum Kind { kFindNode, kPlace, kDelete, kAccept, kFindPath, kTrack } kind;
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

// Fixes the review item the window shows (its camera, frame and knot), whose true label is
// `truth`: a hidden knot's label deleted (D), one within 1 px of the truth accepted (A), any
// other fixed with a Find Node click at the true place (and a Shift+click if that stays in doubt).
inline void FixReviewItem(MainWindow* w, const recon::Label& truth, ScriptedSession* out) {
  Session* s = w->session();
  const int c = w->camera(), t = w->frame(), k = w->knot();
  if (!truth.present()) {
    QTest::keyClick(w, Qt::Key_D);
    out->actions.push_back({Action::kDelete, c, t, k, Eigen::Vector2d::Zero()});
  } else if ((s->document().at(c, t, k).px - truth.px).norm() < 1.0) {
    QTest::keyClick(w, Qt::Key_A);
    out->actions.push_back({Action::kAccept, c, t, k, Eigen::Vector2d::Zero()});
  } else {
    out->actions.push_back({Action::kFindNode, c, t, k, ClickAt(w->view(c), truth.px)});
    if (s->document().at(c, t, k).state != recon::LabelState::kAccepted)
      out->actions.push_back(
          {Action::kPlace, c, t, k, ClickAt(w->view(c), truth.px, Qt::ShiftModifier)});
  }
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
  QTest::keyClick(w, Qt::Key_P, Qt::ControlModifier);
  out.actions.push_back({Action::kFindPath, 0, 0, 0, Eigen::Vector2d::Zero()});
  for (int c = 0; c < s->cameras(); ++c)
    for (int k = 0; k < rows * cols; ++k) {
      const recon::Label& l = s->document().at(c, 0, k);
      if (!want(c, 0, k).present() || l.accepted())
        continue;
      PickKnot(w, k);
      ZoomAt(w->view(c), want(c, 0, k).px, 8);
      out.actions.push_back({Action::kFindNode, c, 0, k, ClickAt(w->view(c), want(c, 0, k).px)});
      if (s->document().at(c, 0, k).state != recon::LabelState::kAccepted)
        out.actions.push_back(
            {Action::kPlace, c, 0, k, ClickAt(w->view(c), want(c, 0, k).px, Qt::ShiftModifier)});
      QTest::keyClick(w, Qt::Key_F, Qt::ControlModifier);
    }
  // 3. Track to the last frame.
  out.finished = TrackForwards(w, &out);
  // 4. The review queue, a frame at a time (docs/gui.md, the workflow). A run stops at the first
  // frame with a label for review and shows its first item; after each fix the window goes on
  // to the frame's next item by itself. The person fixes them, then tracks on from there (T),
  // which also replaces what a run carried from a label in doubt. Items the runs left elsewhere
  // are reached from the queue's first one (Ctrl+Home; Space when the window did not move on).
  const int last = s->frames() - 1;
  auto items = [&] { return s->document().ReviewItems(); };
  auto on_item = [&] {
    const recon::Label& l = s->document().at(w->camera(), w->frame(), w->knot());
    return l.present() && l.state == recon::LabelState::kNeedsReview;
  };
  while (out.finished && out.review_items < max_review_items) {
    if (items().empty() && w->frame() == last) break;  // a run ends on the frame it reached
    if (!items().empty()) {
      if (!on_item()) {
        QTest::keyClick(w, Qt::Key_Home, Qt::ControlModifier);
        ++out.navigation;
      }
      const int round = w->frame();
      for (;;) {
        ++out.review_items;
        FixReviewItem(w, want(w->camera(), w->frame(), w->knot()), &out);
        const auto left = items();
        if (left.empty() || out.review_items >= max_review_items ||
            std::get<1>(left.front()) != round)  // the frame is done (the view shows no diamond)
          break;
        if (!on_item()) {
          QTest::keyClick(w, Qt::Key_Space);
          ++out.navigation;
        }
      }
    }
    out.finished = TrackForwards(w, &out);
  }
  return out;
}

}  // namespace netlab::gui
