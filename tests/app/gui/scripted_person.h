#pragma once
// A scripted person at the workstation, with real mouse, wheel and key events (shared by the
// window's test and bench_gui): seeds the four corners of frame 0 in every camera (a Find Node
// click each, zoomed in; a Shift+click where Find Node finds none or several), runs Find Path
// from the corners (Ctrl+P), clicks every visible knot of frame 0 still without an accepted label
// (as the corners), runs a tracking run to the last frame (T), then walks the review queue
// (Space): a label within 1 px of the truth accepted (A), a hidden knot's deleted (D), any other
// fixed with a Find Node click at the true place (and a Shift+click if that stays in doubt); a
// missing knot (no label) is labeled the same way, or marked hidden where the truth has none: in
// every following frame it is missing in (Shift+D) when the truth has none there either, else
// here (D).

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
  enum Kind { kFindNode, kPlace, kDelete, kAccept, kFindPath, kTrack, kHide, kHideRun } kind;
  int camera = 0, t = 0, knot = 0;
  Eigen::Vector2d px = Eigen::Vector2d::Zero();
};

// Clicks (with `modifiers`) the view at image pixel px; returns the image pixel the click lands
// on (the widget point is whole pixels).
inline Eigen::Vector2d ClickAt(CameraView* view, const Eigen::Vector2d& px,
                               Qt::KeyboardModifiers modifiers = {}) {
  const QPoint point = view->ToWidget(px).toPoint();
  QTest::mouseMove(view, point);
  QTest::mouseClick(view, Qt::LeftButton, modifiers, point);
  return view->ToImage(QPointF(point));
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
  std::vector<Action> actions;  // what the person did that changes labels
  bool finished = false;        // the tracking run ended
  int review_items = 0;         // review items the person went through
};

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
  QTest::keyClick(w, Qt::Key_T);
  out.finished = QTest::qWaitFor([&] { return !w->busy(); }, 600000);
  out.actions.push_back({Action::kTrack, 0, 0, 0, Eigen::Vector2d::Zero()});
  // 4. The review queue.
  for (; out.review_items < max_review_items && !s->document().ReviewItems().empty();
       ++out.review_items) {
    QTest::keyClick(w, Qt::Key_Space);
    const int c = w->camera(), t = w->frame(), k = w->knot();
    const recon::Label& truth_label = want(c, t, k);
    if (!truth_label.present()) {
      const bool labeled = s->document().at(c, t, k).present();
      bool run_hidden = !labeled;  // hidden in every frame it is missing in from here
      for (int u : s->missing().RunFrom(c, t, k)) run_hidden = run_hidden && !want(c, u, k).present();
      if (run_hidden) {
        QTest::keyClick(w, Qt::Key_D, Qt::ShiftModifier);
        out.actions.push_back({Action::kHideRun, c, t, k, Eigen::Vector2d::Zero()});
      } else {
        QTest::keyClick(w, Qt::Key_D);  // a label deleted; a missing knot marked hidden
        out.actions.push_back(
            {labeled ? Action::kDelete : Action::kHide, c, t, k, Eigen::Vector2d::Zero()});
      }
    } else if ((s->document().at(c, t, k).px - truth_label.px).norm() < 1.0) {
      QTest::keyClick(w, Qt::Key_A);
      out.actions.push_back({Action::kAccept, c, t, k, Eigen::Vector2d::Zero()});
    } else {
      out.actions.push_back({Action::kFindNode, c, t, k, ClickAt(w->view(c), truth_label.px)});
      if (s->document().at(c, t, k).state != recon::LabelState::kAccepted)
        out.actions.push_back(
            {Action::kPlace, c, t, k, ClickAt(w->view(c), truth_label.px, Qt::ShiftModifier)});
    }
  }
  return out;
}

}  // namespace netlab::gui
