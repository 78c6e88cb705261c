#include "app/gui/document/labeling_presenter.h"

#include <QStringList>
#include <cmath>

namespace netlab::gui {

QColor LabelColour(const recon::Label& l) {
  if (l.state == recon::LabelState::kNeedsReview) return QColor(255, 140, 0);
  switch (l.source) {
    case recon::LabelSource::kManual: return QColor(0, 230, 255);
    case recon::LabelSource::kFindNode: return QColor(80, 255, 120);
    case recon::LabelSource::kFindPath: return QColor(170, 255, 60);
    case recon::LabelSource::kFillGrid: return QColor(255, 240, 80);
    case recon::LabelSource::kTracked: return QColor(60, 220, 60);
    case recon::LabelSource::kProjected:  // placed from the other cameras: violet
      return QColor(200, 150, 255);
    default: return QColor(200, 200, 255);
  }
}

// ---------------------------------------------------------------------------------------------
// The review queue's walk.

ReviewWalk::ReviewWalk(const ReviewModel* model, const LabelDocument* document,
                       const MissingKnots* missing)
    : model_(model), document_(document), missing_(missing) {}

bool ReviewWalk::UnderReview(int camera, int t, int knot) const {
  const recon::Label& l = document_->at(camera, t, knot);
  return l.present() && l.state == recon::LabelState::kNeedsReview;
}

bool ReviewWalk::InQueue(int camera, int t, int knot) const {
  return UnderReview(camera, t, knot) ||
         (missing_ != nullptr && missing_->Find(camera, t, knot) != nullptr);
}

void ReviewWalk::TookTo(int row) {
  reviewing_ = model_->items()[row];
  reviewing_missing_ = model_->IsMissing(row);
}

int ReviewWalk::NextRow(const LabelKey& here, bool backwards) const {
  if (model_->rowCount() == 0) return -1;
  return backwards ? model_->Previous(here) : model_->Next(here);
}

int ReviewWalk::AdvanceRow(const LabelKey& fixed, bool was_queued) const {
  const auto [c, t, k] = fixed;
  if (!was_queued || reviewing_ != fixed || InQueue(c, t, k) || model_->rowCount() == 0) return -1;
  // The frame's next label for review first; its missing knots (mostly the target's shadow,
  // marked hidden a run at a time with Shift+D once tracking is done) only after a missing knot.
  const std::vector<LabelKey>& items = model_->items();
  const int start = model_->Next(fixed), n = static_cast<int>(items.size());
  int label_row = -1, missing_row = -1;
  for (int i = 0; i < n && label_row < 0; ++i) {
    const int row = (start + i) % n;
    if (items[row].t != t) continue;
    if (!model_->IsMissing(row))
      label_row = row;
    else if (missing_row < 0)
      missing_row = row;
  }
  if (label_row >= 0) return label_row;
  return reviewing_missing_ ? missing_row : -1;
}

int ReviewWalk::StopRow(int t) const {
  int first = -1, label = -1;
  for (int row = 0; row < model_->rowCount() && label < 0; ++row) {
    if (model_->items()[row].t != t) continue;
    if (first < 0) first = row;
    if (!model_->IsMissing(row)) label = row;
  }
  return label >= 0 ? label : first;
}

// ---------------------------------------------------------------------------------------------
// The Fill Grid preview's ghosts and texts.

std::vector<ViewOverlay::Ghost> PreviewGhosts(const LabelDocument& document,
                                              const Session::FillGridPreview& preview, int c,
                                              int t) {
  std::vector<ViewOverlay::Ghost> ghosts;
  if (preview.t != t) return ghosts;
  for (const recon::LabelEdit& e : preview.edits) {
    if (e.camera != c || e.t != t) continue;
    const recon::Label& now = document.at(c, e.t, e.knot);
    ViewOverlay::Ghost g;
    g.knot = e.knot;
    g.px = e.label.present() ? e.label.px : now.px;
    g.review = e.label.state == recon::LabelState::kNeedsReview;
    if (!e.label.present())
      g.kind = ViewOverlay::Ghost::kRemoved;
    else if (!now.present())
      g.kind = ViewOverlay::Ghost::kNew;
    else if (now.accepted() && g.review && now.px == e.label.px)
      g.kind = ViewOverlay::Ghost::kToReview;
    else
      g.kind = ViewOverlay::Ghost::kChanged, g.from = now.px;
    ghosts.push_back(g);
  }
  return ghosts;
}

QString PreviewName(bool from_corners) {
  return from_corners ? "Find Path and Fill Grid preview" : "Fill Grid preview";
}

QString PreviewSummary(const Session::FillGridPreview& p, int frame_number,
                       const QString& accept_keys, const QString& discard_keys) {
  QStringList parts;
  parts << QString("%1 new label%2 (%3 for review)")
               .arg(p.added)
               .arg(p.added == 1 ? "" : "s")
               .arg(p.added_review);
  if (p.confirmed > 0)
    parts << QString("%1 label%2 under review accepted")
                 .arg(p.confirmed)
                 .arg(p.confirmed == 1 ? "" : "s");
  if (p.to_review > 0)
    parts << QString("%1 label%2 to review").arg(p.to_review).arg(p.to_review == 1 ? "" : "s");
  if (p.moved > 0) parts << QString("%1 label%2 moved").arg(p.moved).arg(p.moved == 1 ? "" : "s");
  if (p.changed > 0)
    parts << QString("%1 other change%2").arg(p.changed).arg(p.changed == 1 ? "" : "s");
  return QString(
             "<b>%1, frame %2:</b> %3 — dashed pink marks, not labels yet. "
             "<b>%4</b> accepts (%5), <b>%6</b> discards")
      .arg(PreviewName(p.from_corners))
      .arg(frame_number)
      .arg(parts.join(", "), accept_keys,
           p.from_corners ? "two undo steps: Find Path, Fill Grid" : "one undo step", discard_keys);
}

QString EmptyPreviewMessage(bool from_corners, int frame_number) {
  return from_corners
             ? QString(
                   "Find Path from the corners, frame %1: nothing found; seed three or four "
                   "corners in a camera first (pick the knot, click it)")
                   .arg(frame_number)
             : QString("Fill Grid, frame %1: nothing to add or change; no preview pending")
                   .arg(frame_number);
}

QString AppliedPreviewMessage(const Session::FillGridPreview& preview, int frame_number,
                              int changed) {
  return QString(
             "%1, frame %2: %3 labels set (%4 new, %5 of them for review; %6 under "
             "review accepted; %7 to review)")
      .arg(preview.from_corners ? "Find Path from the corners and Fill Grid" : "Fill Grid")
      .arg(frame_number)
      .arg(changed)
      .arg(preview.added)
      .arg(preview.added_review)
      .arg(preview.confirmed)
      .arg(preview.to_review);
}

QString TrackMessage(const Session::TrackRun& run, int last_frame, int changed) {
  return QString("Tracked to frame %1: %2 labels%3")
      .arg(last_frame)
      .arg(changed)
      .arg(run.cancelled            ? " (cancelled)"
           : run.stopped_for_review ? QString(" (stopped: labels for review in this frame)")
                                    : QString());
}

// ---------------------------------------------------------------------------------------------
// The presenter.

LabelingPresenter::LabelingPresenter(const Session* session, const ReviewModel* model,
                                     const Cursor* cursor)
    : session_(session),
      model_(model),
      cursor_(cursor),
      walk_(model, &session->document(), &session->missing()) {}

ViewOverlay LabelingPresenter::Overlay(int c, const std::vector<Eigen::Vector2d>& candidates,
                                       const Session::FillGridPreview* preview) const {
  const LabelDocument& doc = session_->document();
  const Project& p = session_->project();
  const int t = cursor_->frame(), knot = cursor_->knot();
  ViewOverlay o;
  o.selected_knot = knot;
  int to_fix = 0;  // labels under review and missing knots: which camera to work first
  for (int k = 0; k < p.knots(); ++k) {
    const recon::Label& l = doc.at(c, t, k);
    // (a missing knot has no label: its row's list is searched only for those)
    to_fix += l.present() ? l.state == recon::LabelState::kNeedsReview
                          : session_->missing().Find(c, t, k) != nullptr;
    if (!l.present()) continue;
    o.labels.push_back({k, l.px, LabelColour(l), l.state == recon::LabelState::kNeedsReview});
    // Links to the right and down neighbours that are labeled.
    for (const int n :
         {k % p.cols + 1 < p.cols ? k + 1 : -1, k + p.cols < p.knots() ? k + p.cols : -1})
      if (n >= 0 && doc.at(c, t, n).present()) o.links.emplace_back(l.px, doc.at(c, t, n).px);
  }
  // The selected knot: its epipolar curves from the other cameras' labels, its reprojection.
  for (int other = 0; other < session_->cameras(); ++other) {
    const recon::Label& l = doc.at(other, t, knot);
    if (other == c || !l.present()) continue;
    for (auto& piece : session_->EpipolarCurve(other, l.px, c)) o.epipolar.push_back(piece);
  }
  QString residual;
  const recon::PointEstimate point = session_->Triangulate(t, knot);
  if (point.valid) {
    o.reprojected = session_->rig_camera(c).ProjectWorld(point.position);
    if (doc.at(c, t, knot).present())
      residual = QString(" · residual %1 px")
                     .arg((doc.at(c, t, knot).px - *o.reprojected).norm(), 0, 'f', 2);
  }
  o.candidates = candidates;
  if (preview != nullptr) o.ghosts = PreviewGhosts(doc, *preview, c, t);
  o.caption = QString("%1 · frame %2 · %3 · knot %4%5")
                  .arg(QString::fromStdString(session_->camera_names()[c]))
                  .arg(session_->frame_number(t))
                  .arg(to_fix > 0 ? QString("%1 to fix").arg(to_fix) : QString("nothing to fix"))
                  .arg(cursor_->KnotName(knot), residual);
  // The selected knot without a label here: marked hidden, or where the other cameras put it.
  const recon::Label& l = doc.at(c, t, knot);
  if (l.hidden()) {
    o.caption += " · marked hidden here";
  } else if (const MissingKnot* m = session_->missing().Find(c, t, knot)) {
    o.expected = m->expected_px;
    o.caption += " · no label: expected in the magenta ring";
  }
  return o;
}

QString LabelingPresenter::FrameStatus() const {
  const int t = cursor_->frame();
  return QString("frame %1 (%2 of %3) · t = %4 s · %5")
      .arg(session_->frame_number(t))
      .arg(t + 1)
      .arg(session_->frames())
      .arg(session_->frame_number(t) / session_->fps(), 0, 'f', 4)
      .arg(QString::fromStdString(session_->camera_names()[cursor_->camera()]));
}

QString LabelingPresenter::KnotStatus() const {
  const recon::PointEstimate point = session_->Triangulate(cursor_->frame(), cursor_->knot());
  return QString("knot %1%2")
      .arg(cursor_->KnotName(cursor_->knot()),
           point.valid ? QString(" · RMS residual %1 px").arg(point.rms_px, 0, 'f', 2) : QString());
}

QString LabelingPresenter::Where() const {
  return QString("knot %1 in %2, frame %3")
      .arg(cursor_->KnotName(cursor_->knot()))
      .arg(QString::fromStdString(session_->camera_names()[cursor_->camera()]))
      .arg(session_->frame_number(cursor_->frame()));
}

QString LabelingPresenter::ReviewMessage(int row) const {
  if (model_->IsMissing(row)) {
    const auto [c, t, k] = model_->items()[row];
    return QString("Missing %1 of %2: %3 — click: label it · D: hidden here · Shift+D: and onwards")
        .arg(row + 1)
        .arg(model_->rowCount())
        .arg(QString::fromStdString(session_->missing().Reason(c, t, k)));
  }
  return QString("Review %1 of %2: %3 — A accepts, a click fixes with Find Node, D deletes")
      .arg(row + 1)
      .arg(model_->rowCount())
      .arg(model_->index(row, ReviewModel::kReason).data().toString());
}

QString LabelingPresenter::FindNodeMessage(int c, const recon::FindNodeResult& r) const {
  const int t = cursor_->frame(), knot = cursor_->knot();
  switch (r.status) {
    case recon::FindNodeStatus::kFound: {
      const bool review =
          session_->document().at(c, t, knot).state == recon::LabelState::kNeedsReview;
      // The reason without its own "Find Node: ", which the message already leads with.
      QString reason = QString::fromStdString(session_->document().Reason(c, t, knot));
      if (reason.startsWith("Find Node: ")) reason.remove(0, 11);
      const QString how = r.projected ? "accepted: " + QString::fromStdString(r.why)
                          : review    ? "found, kept for review: " + reason
                                      : "found and accepted";
      return QString("Find Node: knot %1 %2").arg(cursor_->KnotName(knot), how);
    }
    case recon::FindNodeStatus::kNone:
      return "Find Node: no knot in the brush (" + QString::fromStdString(r.why) +
             "); Shift+click places the label exactly";
    case recon::FindNodeStatus::kSeveral:
      return QString(
                 "Find Node: %1 junctions in the brush (red crosses); "
                 "click closer with a smaller brush (-), or Shift+click")
          .arg(r.candidates.size());
  }
  return {};
}

QString LabelingPresenter::ColoursText(const std::optional<Session::KnotColours>& colours) const {
  if (!colours) return "No colouring in the project, or the frame cannot be read.";
  const Session::KnotColours& k = *colours;
  QString text = QString("<b>knot %1 in %2, frame %3</b><br>expected, by link:<br>")
                     .arg(cursor_->KnotName(cursor_->knot()))
                     .arg(QString::fromStdString(session_->camera_names()[cursor_->camera()]))
                     .arg(session_->frame_number(cursor_->frame()));
  for (const auto& link : k.expected)
    text += QString(
                "<span style=\"background-color:rgb(%1,%2,%3)\">&nbsp;&nbsp;&nbsp;&nbsp;"
                "</span> %4 towards %5<br>")
                .arg(std::lround(link.srgb[0]))
                .arg(std::lround(link.srgb[1]))
                .arg(std::lround(link.srgb[2]))
                .arg(QString::fromStdString(link.dye), QString::fromStdString(link.side));
  if (!k.read) {
    const bool labeled =
        session_->document().at(cursor_->camera(), cursor_->frame(), cursor_->knot()).present();
    return text + (labeled ? "<br>reading the yarns…"
                           : "<br>no label here: the yarns are read once it has one");
  }
  using recon::IdentityVerdict;
  const char* colour = k.verdict == IdentityVerdict::kConsistent ? "#1b7837"
                       : k.verdict == IdentityVerdict::kMismatch ? "#b2182b"
                                                                 : "#555555";
  const char* meaning = k.verdict == IdentityVerdict::kConsistent ? "the label's knot"
                        : k.verdict == IdentityVerdict::kMismatch
                            ? "not the label's knot: check it"
                            : "too few yarns read for sure: no evidence either way";
  text += QString("<br>the yarns say: <b style=\"color:%1\">%2</b> (%3)")
              .arg(colour, QString::fromStdString(recon::IdentityVerdictName(k.verdict)), meaning);
  if (!k.knots_read.empty() && k.knots_read.size() <= 3) {
    QStringList names;
    for (int n : k.knots_read) names << cursor_->KnotName(n);
    text += QString(" · they fit %1").arg(names.join(", "));
  }
  if (!k.why.empty())
    text += "<br><small>" + QString::fromStdString(k.why).toHtmlEscaped() + "</small>";
  return text;
}

}  // namespace netlab::gui
