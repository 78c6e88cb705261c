#pragma once
// The labeling room without a window: what its views, its status bar, its preview banner and its
// knot colours panel show, and the review queue's walk (which item Space, a fix or a tracking
// run's stop goes to). The window lays these out, paints them and forwards the person's actions;
// tests check the rules here directly.
//
//   ReviewWalk walk(&review_model, &document, &missing);
//   walk.TookTo(row);                                  // Space took the person to row
//   int next = walk.AdvanceRow(fixed, was_queued);     // the frame's next item after a fix, or -1
//
//   LabelingPresenter presenter(&session, &review_model, &cursor);
//   view->SetOverlay(presenter.Overlay(c, candidates, preview));

#include <Eigen/Core>
#include <QColor>
#include <QString>
#include <optional>
#include <string>
#include <vector>

#include "app/gui/document/cursor.h"
#include "app/gui/document/label_document.h"
#include "app/gui/document/missing_knots.h"
#include "app/gui/document/review_model.h"
#include "app/gui/document/session.h"
#include "app/gui/document/view_overlay.h"

namespace netlab::gui {

// A label's colour in the views and the Net grid: by state first (under review: orange), then by
// where it came from (person cyan, Find Node green, placed from the other cameras violet, ...).
QColor LabelColour(const recon::Label& label);

// The review queue's walk: which row the window goes to. Reads the review model (its rows, in the
// queue's order), the document and the missing knots (null: none).
class ReviewWalk {
 public:
  ReviewWalk(const ReviewModel* model, const LabelDocument* document, const MissingKnots* missing);

  // (camera, t, knot) has a label under review.
  bool UnderReview(int camera, int t, int knot) const;
  // ... or is a missing knot: an item of the queue.
  bool InQueue(int camera, int t, int knot) const;

  // The window took the person to row `row` (Space, Ctrl+Home, a row activated, a run's stop).
  void TookTo(int row);
  // The queue's item it last took the person to, and whether it was a missing knot.
  const std::optional<LabelKey>& reviewing() const { return reviewing_; }
  bool reviewing_missing() const { return reviewing_missing_; }

  // The row after (before, when `backwards`) `here` in the queue, wrapping; -1 when empty.
  int NextRow(const LabelKey& here, bool backwards = false) const;
  // After the person fixed `fixed` (accepted, deleted, hidden, placed or found again and no
  // longer in doubt), when it was in the queue before (`was_queued`): the same frame's next label
  // for review, or, only after a missing knot, its next missing knot; -1 for none. Only an item
  // the window took the person to moves the window: a knot labeled on their own (a seed) never
  // does, nor one still in the queue.
  int AdvanceRow(const LabelKey& fixed, bool was_queued) const;
  // Where a tracking run stopped for review in frame row t: that frame's first label for review
  // (what stopped it; its missing knots wait), else its first item; -1 when none.
  int StopRow(int t) const;

 private:
  const ReviewModel* model_;
  const LabelDocument* document_;
  const MissingKnots* missing_;
  std::optional<LabelKey> reviewing_;
  bool reviewing_missing_ = false;
};

// What accepting `preview` would do in camera c, as the view draws it: ghosts of new, changed,
// to-review and removed labels against the labels of `document` now. Empty when the preview is
// of another frame row than `t`.
std::vector<ViewOverlay::Ghost> PreviewGhosts(const LabelDocument& document,
                                              const Session::FillGridPreview& preview, int c,
                                              int t);
// "Fill Grid preview" or "Find Path and Fill Grid preview".
QString PreviewName(bool from_corners);
// The preview banner (rich text): what the preview would change, and the keys that answer it.
// `frame_number`: the recording's number of the preview's frame row.
QString PreviewSummary(const Session::FillGridPreview& preview, int frame_number,
                       const QString& accept_keys, const QString& discard_keys);
// The status bar after a preview of frame `frame_number` found nothing to do.
QString EmptyPreviewMessage(bool from_corners, int frame_number);
// The status bar after a preview was applied, changing `changed` labels.
QString AppliedPreviewMessage(const Session::FillGridPreview& preview, int frame_number,
                              int changed);
// The status bar after a tracking run was applied, changing `changed` labels; `last_frame`: the
// recording's number of its last frame row done.
QString TrackMessage(const Session::TrackRun& run, int last_frame, int changed);

class LabelingPresenter {
 public:
  // `session`, `model` and `cursor` must outlive the presenter.
  LabelingPresenter(const Session* session, const ReviewModel* model, const Cursor* cursor);

  const ReviewWalk& walk() const { return walk_; }
  ReviewWalk& walk() { return walk_; }

  // The overlay of camera c at the cursor's frame: every label coloured by state and source,
  // links between labeled neighbours, the selected knot's epipolar curves from the other
  // cameras' labels, its reprojection and residual, the expected ring of a missing knot or the
  // hidden mark, Find Node's `candidates`, the pending `preview`'s ghosts (null: none), and the
  // caption (camera, frame, how many to fix, knot, residual).
  ViewOverlay Overlay(int c, const std::vector<Eigen::Vector2d>& candidates,
                      const Session::FillGridPreview* preview) const;

  // The status bar's permanent readouts: "frame 12 (13 of 31) · t = 0.0670 s · cam0" and
  // "knot (2, 3) · RMS residual 0.41 px".
  QString FrameStatus() const;
  QString KnotStatus() const;
  // "knot (2, 3) in cam0, frame 12".
  QString Where() const;
  // The status bar at the queue's row `row` (a label for review or a missing knot).
  QString ReviewMessage(int row) const;
  // The status bar after Find Node at the cursor's knot in camera c.
  QString FindNodeMessage(int c, const recon::FindNodeResult& result) const;
  // The knot colours panel (rich text) for the cursor's knot, from its colour check (nullopt: no
  // colouring or no readable frame), or its expected colours alone (Session::ExpectedColours:
  // the knot has no label, or its yarns are being read).
  QString ColoursText(const std::optional<Session::KnotColours>& colours) const;

 private:
  const Session* session_;
  const ReviewModel* model_;
  const Cursor* cursor_;
  ReviewWalk walk_;
};

}  // namespace netlab::gui
