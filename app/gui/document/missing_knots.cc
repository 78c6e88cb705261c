#include "app/gui/document/missing_knots.h"

#include <algorithm>
#include <cstdio>
#include <optional>
#include <stdexcept>
#include <tuple>

#include "libreconstruct/geometry/triangulation.h"
#include "libreconstruct/labeling/label_engine.h"

namespace netlab::gui {
namespace {

// Whether a triangulation of `views` observations is one the person can trust for "expected
// here": every view an inlier, each within `max_px`.
bool Consistent(const recon::PointEstimate& e, size_t views, double max_px) {
  if (!e.valid || !e.outliers.empty() || e.residual_px.size() != views) return false;
  for (double r : e.residual_px)
    if (!(r <= max_px)) return false;  // NaN (behind a camera) fails too
  return true;
}

// Where `camera` sees the world point p: in front of it, inside its image by `margin` px, and
// its own projection (the pixel undistorts back to p's ray: a lens model's polynomial can fold a
// point far outside the field of view into the image).
std::optional<Eigen::Vector2d> SeenAt(const calib::Camera& camera, const Eigen::Vector3d& p,
                                      double margin) {
  const Eigen::Vector3d p_in_cam = camera.cam_from_world * p;
  if (!(p_in_cam.z() > 0.0)) return std::nullopt;
  const Eigen::Vector2d q = calib::Project(camera.intrinsics, p_in_cam);
  const calib::CameraIntrinsics& in = camera.intrinsics;
  if (!q.allFinite() || q.x() < margin || q.y() < margin || q.x() > in.width - 1 - margin ||
      q.y() > in.height - 1 - margin)
    return std::nullopt;
  const Eigen::Vector2d ray = p_in_cam.head<2>() / p_in_cam.z();
  const Eigen::Vector2d back = calib::UndistortPoint(in, q);
  if (!back.allFinite() || (back - ray).norm() > 1e-4 * (1.0 + ray.norm())) return std::nullopt;
  return q;
}

// Whether camera c has a label of one of knot k's grid neighbours in frame row t.
bool HasLabeledNeighbour(const recon::LabelSet& labels, int c, int t, int k) {
  for (int n : recon::GridSlots(labels.rows, labels.cols, k))
    if (n >= 0 && labels.at(c, t, n).present()) return true;
  return false;
}

}  // namespace

bool MissingKnotsOptions::IsValid(std::string* why) const {
  if (!(max_residual_px > 0.0)) {
    *why = "max_residual_px must be > 0 (px)";
    return false;
  }
  if (!(margin_px >= 0.0)) {
    *why = "margin_px must be >= 0 (px)";
    return false;
  }
  return true;
}

std::vector<MissingKnot> FindMissingKnots(const recon::LabelSet& labels, const calib::Rig& rig,
                                          const std::vector<int>& rig_index, int t,
                                          const MissingKnotsOptions& options) {
  std::vector<MissingKnot> out;
  const int cameras = static_cast<int>(labels.cameras.size());
  recon::TriangulationOptions topt;
  topt.outlier_threshold_px = options.max_residual_px;
  for (int k = 0; k < labels.knots(); ++k) {
    // The cameras that see the knot (accepted labels), and those that have nothing of it.
    std::vector<recon::Observation> views;
    std::vector<int> seen_in, open;
    for (int c = 0; c < cameras; ++c) {
      const recon::Label& l = labels.at(c, t, k);
      if (l.accepted()) {
        views.push_back({rig_index[c], l.px});
        seen_in.push_back(c);
      } else if (!l.present() && !l.hidden() &&
                 (!options.need_labeled_neighbour || HasLabeledNeighbour(labels, c, t, k))) {
        open.push_back(c);
      }
    }
    if (seen_in.size() < 2 || open.empty()) continue;  // most knots: cheap to skip
    // Where the seeing cameras agree it is, when they agree.
    const recon::PointEstimate e = recon::TriangulatePoint(rig, views, topt);
    if (!Consistent(e, views.size(), options.max_residual_px)) continue;
    for (int c : open)
      if (const auto q = SeenAt(rig.cameras[rig_index[c]], e.position, options.margin_px))
        out.push_back({c, t, k, *q, seen_in, e.rms_px});
  }
  std::sort(out.begin(), out.end(), [](const MissingKnot& a, const MissingKnot& b) {
    return std::tie(a.camera, a.knot) < std::tie(b.camera, b.knot);
  });
  return out;
}

std::string MissingReason(const MissingKnot& missing, const std::vector<std::string>& cameras) {
  std::string seen;
  for (int c : missing.seen_in) seen += (seen.empty() ? "" : ", ") + cameras[c];
  char where[96];
  std::snprintf(where, sizeof where, "; expected near (%.1f, %.1f)", missing.expected_px.x(),
                missing.expected_px.y());
  return "no label; seen in " + seen + where;
}

MissingKnots::MissingKnots(const LabelDocument* document, const calib::Rig* rig,
                           std::vector<int> rig_index, MissingKnotsOptions options,
                           QObject* parent)
    : QObject(parent),
      document_(document),
      rig_(rig),
      rig_index_(std::move(rig_index)),
      options_(options) {
  std::string why;
  if (!options_.IsValid(&why)) throw std::invalid_argument("missing knots: " + why);
  if (rig_index_.size() != document_->labels().cameras.size())
    throw std::invalid_argument("missing knots: one rig camera per camera of the labels");
  // Every frame row now; later only the rows an edit names.
  const int frames = document_->labels().frames();
  by_row_.resize(frames);
  for (int t = 0; t < frames; ++t) {
    by_row_[t] = FindMissingKnots(document_->labels(), *rig_, rig_index_, t, options_);
    size_ += static_cast<int>(by_row_[t].size());
  }
  connect(document_, &LabelDocument::labelsChanged, this, &MissingKnots::Recount);
}

void MissingKnots::Recount(const QList<int>& frames) {
  for (int t : frames) {
    if (t < 0 || t >= static_cast<int>(by_row_.size())) continue;
    size_ -= static_cast<int>(by_row_[t].size());
    by_row_[t] = FindMissingKnots(document_->labels(), *rig_, rig_index_, t, options_);
    size_ += static_cast<int>(by_row_[t].size());
  }
  emit changed(frames);
}

std::vector<LabelKey> MissingKnots::Items() const {
  std::vector<LabelKey> items;
  items.reserve(size_);
  for (const std::vector<MissingKnot>& row : by_row_)
    for (const MissingKnot& m : row) items.emplace_back(m.camera, m.t, m.knot);
  return items;
}

const MissingKnot* MissingKnots::Find(int camera, int t, int knot) const {
  if (t < 0 || t >= static_cast<int>(by_row_.size())) return nullptr;
  for (const MissingKnot& m : by_row_[t])
    if (m.camera == camera && m.knot == knot) return &m;
  return nullptr;
}

std::string MissingKnots::Reason(int camera, int t, int knot) const {
  const MissingKnot* m = Find(camera, t, knot);
  return m ? MissingReason(*m, document_->labels().cameras) : "";
}

std::set<int> MissingKnots::Frames() const {
  std::set<int> frames;
  for (int t = 0; t < static_cast<int>(by_row_.size()); ++t)
    if (!by_row_[t].empty()) frames.insert(t);
  return frames;
}

std::vector<int> MissingKnots::RunFrom(int camera, int t, int knot) const {
  std::vector<int> run;
  for (int u = t; Find(camera, u, knot); ++u) run.push_back(u);
  return run;
}

}  // namespace netlab::gui
