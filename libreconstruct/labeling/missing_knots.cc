#include "libreconstruct/labeling/missing_knots.h"

#include <algorithm>
#include <cstdio>
#include <optional>
#include <tuple>

#include "libreconstruct/geometry/triangulation.h"
#include "libreconstruct/labeling/label_engine.h"

namespace netlab::recon {
namespace {

// Whether a triangulation of `views` observations is one the person can trust for "expected
// here": every view an inlier, each within `max_px`.
bool Consistent(const PointEstimate& e, size_t views, double max_px) {
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
bool HasLabeledNeighbour(const LabelSet& labels, int c, int t, int k) {
  for (int n : GridSlots(labels.rows, labels.cols, k))
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

std::vector<MissingKnot> FindMissingKnots(const LabelSet& labels, const calib::Rig& rig,
                                          const std::vector<int>& rig_index, int t,
                                          const MissingKnotsOptions& options) {
  std::vector<MissingKnot> out;
  const int cameras = static_cast<int>(labels.cameras.size());
  TriangulationOptions topt;
  topt.outlier_threshold_px = options.max_residual_px;
  for (int k = 0; k < labels.knots(); ++k) {
    // The cameras that see the knot (accepted labels), and those that have nothing of it.
    std::vector<Observation> views;
    std::vector<int> seen_in, open;
    for (int c = 0; c < cameras; ++c) {
      const Label& l = labels.at(c, t, k);
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
    const PointEstimate e = TriangulatePoint(rig, views, topt);
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

}  // namespace netlab::recon
