#include "libreconstruct/labeling/missing_knots.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <optional>
#include <tuple>
#include <unordered_map>

#include "libreconstruct/labeling/label_engine.h"

namespace netlab::recon {

Eigen::Vector2d InsideOuterEdgeByAxisPx(const Eigen::Vector2d& q, int width, int height) {
  if (!q.allFinite()) return Eigen::Vector2d::Constant(std::numeric_limits<double>::quiet_NaN());
  return {std::min(q.x() + 0.5, width - 0.5 - q.x()), std::min(q.y() + 0.5, height - 0.5 - q.y())};
}

double InsideOuterEdgePx(const Eigen::Vector2d& q, int width, int height) {
  return InsideOuterEdgeByAxisPx(q, width, height).minCoeff();
}

namespace {

// Does the segment from `from` to `to` pass through the box (strictly before `to`)?
bool SegmentHitsBox(const Eigen::Vector3d& from, const Eigen::Vector3d& to,
                    const Eigen::Vector3d& center, const Eigen::Quaterniond& orientation,
                    const Eigen::Vector3d& half) {
  const Eigen::Quaterniond inv = orientation.conjugate();
  const Eigen::Vector3d a = inv * (from - center), d = inv * (to - from);
  double t0 = 0.0, t1 = 1.0 - 1e-9;
  for (int i = 0; i < 3; ++i) {
    if (std::abs(d[i]) < 1e-15) {
      if (std::abs(a[i]) > half[i]) return false;
      continue;
    }
    double ta = (-half[i] - a[i]) / d[i], tb = (half[i] - a[i]) / d[i];
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta);
    t1 = std::min(t1, tb);
    if (t0 > t1) return false;
  }
  return true;
}

bool SegmentHitsBall(const Eigen::Vector3d& from, const Eigen::Vector3d& to,
                     const Eigen::Vector3d& center, double radius) {
  if (!(radius > 0.0)) return false;
  const Eigen::Vector3d d = to - from;
  const double s = std::clamp((center - from).dot(d) / d.squaredNorm(), 0.0, 1.0 - 1e-9);
  return (from + s * d - center).norm() < radius;
}

// Whether a triangulation of `views` observations is one the person can trust for "expected
// here": every view an inlier, each within `max_px`, and a usable ray geometry.
// "" when it is; else why not.
std::string Inconsistency(const PointEstimate& e, size_t views, const MissingKnotsOptions& o) {
  if (!e.valid || !e.outliers.empty() || e.residual_px.size() != views)
    return "do not triangulate to one point";
  for (double r : e.residual_px)
    if (!(r <= o.max_residual_px)) {  // NaN (behind a camera) fails too
      char s[96];
      std::snprintf(s, sizeof s, "disagree (a residual of %.1f px, more than %.1f)", r,
                    o.max_residual_px);
      return s;
    }
  if (!UsableGeometry(e, o.max_unit_sigma_mm * 1e-3))
    return "have rays too near head-on to place it (UsableGeometry)";
  return "";
}

std::string Px(const Eigen::Vector2d& q) {
  char s[64];
  std::snprintf(s, sizeof s, "(%.1f, %.1f)", q.x(), q.y());
  return s;
}

// A knot's point (1.-3. of the header) and, where the cameras place it (1.), its covariance for
// 1 px of label noise and the label noise taken (px per axis); zero for a rough point (2., 3.),
// whose error is not known to the pixel.
struct KnotPlace {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  Eigen::Matrix3d unit_covariance = Eigen::Matrix3d::Zero();  // m^2 / px^2
  double label_sigma_px = 0.0;
};

// How far beyond the image's outer edge `camera` may see the point of `place` and still list it
// (px, along x and y; negative: the least it must lie inside): its projection's standard
// deviation times edge_sigmas, at most beyond_edge_px; a rough point's beyond_edge_px (header,
// MissingKnotsOptions).
Eigen::Vector2d EdgeSlack(const calib::Camera& camera, const KnotPlace& place,
                          const MissingKnotsOptions& o) {
  if (o.margin_px > 0.0) return Eigen::Vector2d::Constant(-o.margin_px);
  Eigen::Vector2d px;
  Eigen::Matrix<double, 2, 3> j;
  if (!(place.label_sigma_px > 0.0) || !PixelAndJacobian(camera, place.position, &px, &j))
    return Eigen::Vector2d::Constant(o.beyond_edge_px);  // a rough point: its error not known
  const Eigen::Matrix2d cov = j * place.unit_covariance * j.transpose();
  Eigen::Vector2d slack;
  for (int a = 0; a < 2; ++a) {
    slack[a] = o.edge_sigmas * place.label_sigma_px * std::sqrt(std::max(cov(a, a), 0.0));
    slack[a] = std::isfinite(slack[a]) ? std::min(slack[a], o.beyond_edge_px) : o.beyond_edge_px;
  }
  return slack;
}

// Where `camera` sees the point of `place`: in front of it, inside its image's outer edge (or
// beyond it by at most EdgeSlack along each axis), and its own projection (the pixel undistorts
// back to the point's ray: a lens model's polynomial can fold a point far outside the field of
// view into the image). `why` (when given) says why not.
std::optional<Eigen::Vector2d> SeenAt(const calib::Camera& camera, const KnotPlace& place,
                                      const MissingKnotsOptions& o, std::string* why = nullptr) {
  const Eigen::Vector3d p_in_cam = camera.cam_from_world * place.position;
  if (!(p_in_cam.z() > 0.0)) {
    if (why) *why = "its point is behind the camera";
    return std::nullopt;
  }
  const Eigen::Vector2d q = calib::Project(camera.intrinsics, p_in_cam);
  const calib::CameraIntrinsics& in = camera.intrinsics;
  const Eigen::Vector2d slack = EdgeSlack(camera, place, o);
  const Eigen::Vector2d inside = InsideOuterEdgeByAxisPx(q, in.width, in.height);
  if (!(inside.x() >= -slack.x() && inside.y() >= -slack.y())) {
    if (why) {
      const int a = inside.x() < inside.y() ? 0 : 1;  // the axis it is furthest out along
      char s[192];
      std::snprintf(s, sizeof s,
                    "its point projects to %s, outside the image (%.2f px beyond its edge; its "
                    "error allows %.2f)",
                    Px(q).c_str(), -inside[a], std::max(slack[a], 0.0));
      *why = inside.allFinite() ? s : "its point projects to " + Px(q) + ", outside the image";
    }
    return std::nullopt;
  }
  const Eigen::Vector2d ray = p_in_cam.head<2>() / p_in_cam.z();
  const Eigen::Vector2d back = calib::UndistortPoint(in, q);
  if (!back.allFinite() || (back - ray).norm() > 1e-4 * (1.0 + ray.norm())) {
    if (why) *why = "its point projects to " + Px(q) + " only by the lens model's fold";
    return std::nullopt;
  }
  return q;
}

// Whether camera c has a label of one of knot k's grid neighbours in frame row t.
bool HasLabeledNeighbour(const LabelSet& labels, int c, int t, int k) {
  for (int n : GridSlots(labels.rows, labels.cols, k))
    if (n >= 0 && labels.at(c, t, n).present()) return true;
  return false;
}

// A knot's point from the cameras' labels in one frame row (1. of the header); where only one
// camera has a label, that camera and its label.
struct ViewsPoint {
  bool valid = false;
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  Eigen::Matrix3d unit_covariance = Eigen::Matrix3d::Zero();  // m^2 / px^2
  std::vector<int> seen_in, under_review;
  double rms_px = 0.0;
  int lone_camera = -1;  // the one camera with a label (accepted or under review), or -1
  Eigen::Vector2d lone_px = Eigen::Vector2d::Zero();
  std::string why;  // when not valid: why the cameras give no point
};

// The points of frame rows computed once each, on demand: (row, knot) -> ViewsPoint.
class Points {
 public:
  Points(const LabelSet& labels, const calib::Rig& rig, const std::vector<int>& rig_index,
         const MissingKnotsOptions& o)
      : labels_(labels), rig_(rig), rig_index_(rig_index), o_(o) {
    topt_.outlier_threshold_px = o.max_residual_px;
  }

  const ViewsPoint& At(int s, int k) {
    const size_t key = static_cast<size_t>(s) * labels_.knots() + k;
    auto it = cache_.find(key);
    if (it == cache_.end()) it = cache_.emplace(key, Compute(s, k)).first;
    return it->second;
  }

  const LabelSet& labels() const { return labels_; }
  const calib::Rig& rig() const { return rig_; }
  const std::vector<int>& rig_index() const { return rig_index_; }

 private:
  ViewsPoint Compute(int s, int k) const {
    ViewsPoint out;
    // Accepted labels first; labels under review only where those are fewer than two.
    for (bool with_review : {false, true}) {
      std::vector<Observation> views;
      std::vector<int> seen, review;
      for (int c = 0; c < static_cast<int>(labels_.cameras.size()); ++c) {
        const Label& l = labels_.at(c, s, k);
        if (l.accepted() || (with_review && l.present() && l.state == LabelState::kNeedsReview)) {
          views.push_back({rig_index_[c], l.px});
          seen.push_back(c);
          if (!l.accepted()) review.push_back(c);
        }
      }
      if (views.size() == 1) {
        out.lone_camera = seen[0];
        out.lone_px = views[0].px;
      }
      if (with_review && review.empty()) break;  // nothing more than the accepted ones
      if (views.size() < 2) {
        out.why = views.empty() ? "no other camera has a label of it"
                                : "only " + labels_.cameras[seen[0]] + " has a label of it";
        continue;
      }
      out.lone_camera = -1;
      const PointEstimate e = TriangulatePoint(rig_, views, topt_);
      const std::string inconsistency = Inconsistency(e, views.size(), o_);
      if (!inconsistency.empty()) {
        std::string names;
        for (int c : seen) names += (names.empty() ? "" : ", ") + labels_.cameras[c];
        out.why = "the labels in " + names + " " + inconsistency;
        if (!with_review) return out;  // accepted labels that do not agree: no point
        continue;
      }
      out.valid = true;
      out.position = e.position;
      out.unit_covariance = e.unit_covariance;
      out.seen_in = seen;
      out.under_review = review;
      out.rms_px = e.rms_px;
      return out;
    }
    return out;
  }

  const LabelSet& labels_;
  const calib::Rig& rig_;
  const std::vector<int>& rig_index_;
  const MissingKnotsOptions& o_;
  TriangulationOptions topt_;
  std::unordered_map<size_t, ViewsPoint> cache_;
};

// A rough point of a knot and how far it may be off (m).
struct Rough {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  double tolerance_m = 0.0;
};

// The knot's point from its grid neighbours' points in row t (2. of the header): the grid lines
// through it that have points putting it within the tolerance of each other.
std::optional<Rough> FromNeighbours(Points& points, int t, int k, const MissingKnotsOptions& o) {
  const LabelSet& l = points.labels();
  const int r = k / l.cols, c = k % l.cols;
  const auto at = [&](int rr, int cc) -> const ViewsPoint* {
    if (rr < 0 || cc < 0 || rr >= l.rows || cc >= l.cols) return nullptr;
    const ViewsPoint& p = points.At(t, rr * l.cols + cc);
    return p.valid ? &p : nullptr;
  };
  std::vector<Eigen::Vector3d> guesses;
  double link = 0.0;
  int links = 0;
  for (const auto& [dr, dc] : {std::pair{0, 1}, std::pair{1, 0}}) {
    const ViewsPoint* before = at(r - dr, c - dc);
    const ViewsPoint* after = at(r + dr, c + dc);
    if (before && after) {
      guesses.push_back(0.5 * (before->position + after->position));
      link += 0.5 * (after->position - before->position).norm();
      ++links;
      continue;
    }
    for (const ViewsPoint* near : {before, after}) {
      if (!near) continue;
      const int sign = near == before ? -1 : 1;
      const ViewsPoint* far = at(r + 2 * sign * dr, c + 2 * sign * dc);
      if (!far) continue;
      guesses.push_back(2.0 * near->position - far->position);
      link += (near->position - far->position).norm();
      ++links;
    }
  }
  if (guesses.empty()) return std::nullopt;
  Rough out;
  out.tolerance_m = 0.5 * o.neighbour_agreement * link / links;
  for (const Eigen::Vector3d& g : guesses) out.position += g;
  out.position /= static_cast<double>(guesses.size());
  for (const Eigen::Vector3d& g : guesses)
    if ((g - out.position).norm() > out.tolerance_m) return std::nullopt;
  return out;
}

// The knot's point from its own points in the rows around t (3. of the header).
std::optional<Rough> FromMotion(Points& points, int t, int k, const MissingKnotsOptions& o,
                                std::vector<int>* rows) {
  const int frames = points.labels().frames();
  const auto at = [&](int s) -> const ViewsPoint* {
    if (s < 0 || s >= frames) return nullptr;
    const ViewsPoint& p = points.At(s, k);
    return p.valid ? &p : nullptr;
  };
  Rough out;
  // Between a row before and one after, the nearest first.
  for (int span = 2; span <= 2 * o.motion_rows; ++span)
    for (int before = 1; before < span; ++before) {
      const int after = span - before;
      if (before > o.motion_rows || after > o.motion_rows) continue;
      const ViewsPoint* a = at(t - before);
      const ViewsPoint* b = at(t + after);
      if (!a || !b) continue;
      *rows = {t - before, t + after};
      const double w = static_cast<double>(before) / span;
      out.position = (1.0 - w) * a->position + w * b->position;
      out.tolerance_m =
          0.5 * o.neighbour_agreement * (b->position - a->position).norm() + o.motion_tolerance_m;
      return out;
    }
  // Carried on from two rows on one side.
  for (int sign : {-1, 1})
    for (int near = 1; near < o.motion_rows; ++near)
      for (int far = near + 1; far <= o.motion_rows; ++far) {
        const ViewsPoint* a = at(t + sign * near);
        const ViewsPoint* b = at(t + sign * far);
        if (!a || !b) continue;
        *rows = {t + sign * near, t + sign * far};
        const double f = static_cast<double>(far) / (far - near);
        out.position = f * a->position + (1.0 - f) * b->position;
        out.tolerance_m = 0.5 * o.neighbour_agreement * f * (b->position - a->position).norm() +
                          o.motion_tolerance_m;
        return out;
      }
  return std::nullopt;
}

// The point of `camera`'s ray through `px` nearest to `rough`, when within its tolerance.
std::optional<Eigen::Vector3d> OnRay(const calib::Camera& camera, const Eigen::Vector2d& px,
                                     const Rough& rough) {
  const Eigen::Vector2d xy = calib::UndistortPoint(camera.intrinsics, px);
  if (!xy.allFinite()) return std::nullopt;
  const Eigen::Vector3d d =
      (camera.cam_from_world.rotation.conjugate() * Eigen::Vector3d(xy.x(), xy.y(), 1.0))
          .normalized();
  const Eigen::Vector3d c = camera.Center();
  const double depth = (rough.position - c).dot(d);
  if (!(depth > 0.0)) return std::nullopt;
  const Eigen::Vector3d p = c + depth * d;
  if ((p - rough.position).norm() > rough.tolerance_m) return std::nullopt;
  return p;
}

// Knot k's point in frame row t (1.-3. of the header), with where it came from in `out`; none,
// with `why` (when given) saying why, when nothing places it.
std::optional<KnotPlace> KnotPoint(Points& points, int t, int k, const MissingKnotsOptions& options,
                                   MissingKnot* out, std::string* why) {
  const LabelSet& labels = points.labels();
  MissingKnot& m = *out;
  m.t = t;
  m.knot = k;
  // The cameras; else one camera's ray where its neighbours or its motion put it; else its
  // neighbours (two grid lines agreeing) or its motion alone.
  const ViewsPoint& v = points.At(t, k);
  if (v.valid) {
    m.seen_in = v.seen_in;
    m.under_review = v.under_review;
    m.rms_px = v.rms_px;
    return KnotPlace{v.position, v.unit_covariance, std::max(options.label_sigma_px, v.rms_px)};
  }
  std::optional<Rough> rough = FromNeighbours(points, t, k, options);
  m.basis = MissingBasis::kNeighbours;
  if (!rough) {
    rough = FromMotion(points, t, k, options, &m.rows);
    m.basis = MissingBasis::kMotion;
  }
  if (!rough) {
    if (why)
      *why = "no point: " + v.why +
             ", its grid neighbours' points do not place it and its own points in the rows "
             "around do not";
    return std::nullopt;
  }
  // On the ray of the one camera with a label, where it passes near; else (no label, or a label
  // off the rough point: a wrong one) the rough point itself.
  std::optional<Eigen::Vector3d> p;
  if (v.lone_camera >= 0)
    p = OnRay(points.rig().cameras[points.rig_index()[v.lone_camera]], v.lone_px, *rough);
  if (p) {
    m.seen_in = {v.lone_camera};
    if (!labels.at(v.lone_camera, t, k).accepted()) m.under_review = {v.lone_camera};
    return KnotPlace{*p};
  }
  return KnotPlace{rough->position};
}

std::string Names(const std::vector<int>& cameras, const std::vector<std::string>& names) {
  std::string s;
  for (int c : cameras) s += (s.empty() ? "" : ", ") + names[c];
  return s;
}

}  // namespace

bool TargetHides(const Target& target, const Eigen::Vector3d& from, const Eigen::Vector3d& to,
                 double time_s, double grow_m) {
  for (const TargetSolid& s : target.solids) {
    const Eigen::Vector3d center = s.center + time_s * s.velocity;
    if (s.shape == TargetSolid::Shape::kBox) {
      const Eigen::Vector3d half = (s.half_extents.array() + grow_m).max(0.0).matrix();
      if (half.minCoeff() > 0.0 && SegmentHitsBox(from, to, center, s.orientation, half))
        return true;
    } else if (SegmentHitsBall(from, to, center, s.radius + grow_m)) {
      return true;
    }
  }
  return false;
}

bool MissingKnotsOptions::IsValid(std::string* why) const {
  if (!(max_residual_px > 0.0)) {
    *why = "max_residual_px must be > 0 (px)";
    return false;
  }
  if (!(max_unit_sigma_mm > 0.0)) {
    *why = "max_unit_sigma_mm must be > 0 (mm)";
    return false;
  }
  if (!(margin_px >= 0.0)) {
    *why = "margin_px must be >= 0 (px)";
    return false;
  }
  if (!(beyond_edge_px >= 0.0)) {
    *why = "beyond_edge_px must be >= 0 (px)";
    return false;
  }
  if (!(label_sigma_px >= 0.0)) {
    *why = "label_sigma_px must be >= 0 (px)";
    return false;
  }
  if (!(edge_sigmas >= 0.0)) {
    *why = "edge_sigmas must be >= 0";
    return false;
  }
  if (!(neighbour_agreement >= 0.0)) {
    *why = "neighbour_agreement must be >= 0";
    return false;
  }
  if (!(motion_tolerance_m >= 0.0)) {
    *why = "motion_tolerance_m must be >= 0 (m)";
    return false;
  }
  if (motion_rows < 0) {
    *why = "motion_rows must be >= 0";
    return false;
  }
  if (!target.empty() && !(target.fps > 0.0)) {
    *why = "target.fps must be > 0 (frames per second)";
    return false;
  }
  return true;
}

std::vector<MissingKnot> FindMissingKnots(const LabelSet& labels, const calib::Rig& rig,
                                          const std::vector<int>& rig_index, int t,
                                          const MissingKnotsOptions& options) {
  std::vector<MissingKnot> out;
  const int cameras = static_cast<int>(labels.cameras.size());
  Points points(labels, rig, rig_index, options);
  const double time_s = options.target.empty() ? 0.0 : labels.frame_index[t] / options.target.fps;
  for (int k = 0; k < labels.knots(); ++k) {
    // The cameras that have nothing of the knot.
    std::vector<int> open;
    for (int c = 0; c < cameras; ++c) {
      const Label& l = labels.at(c, t, k);
      if (!l.present() && !l.hidden() &&
          (!options.need_labeled_neighbour || HasLabeledNeighbour(labels, c, t, k)))
        open.push_back(c);
    }
    if (open.empty()) continue;
    MissingKnot m;
    const std::optional<KnotPlace> p = KnotPoint(points, t, k, options, &m, nullptr);
    if (!p) continue;
    for (int c : open) {
      const calib::Camera& camera = rig.cameras[rig_index[c]];
      const auto q = SeenAt(camera, *p, options);
      if (!q) continue;
      if (TargetHides(options.target, camera.Center(), p->position, time_s, options.target_grow_m))
        continue;
      m.camera = c;
      m.expected_px = *q;
      out.push_back(m);
    }
  }
  std::sort(out.begin(), out.end(), [](const MissingKnot& a, const MissingKnot& b) {
    return std::tie(a.camera, a.knot) < std::tie(b.camera, b.knot);
  });
  return out;
}

std::string WhyNotMissing(const LabelSet& labels, const calib::Rig& rig,
                          const std::vector<int>& rig_index, int camera, int t, int knot,
                          const MissingKnotsOptions& options) {
  const Label& l = labels.at(camera, t, knot);
  if (l.present()) return "it has a label";
  if (l.hidden()) return "it is marked hidden";
  if (options.need_labeled_neighbour && !HasLabeledNeighbour(labels, camera, t, knot))
    return "none of its grid neighbours has a label in " + labels.cameras[camera];
  Points points(labels, rig, rig_index, options);
  MissingKnot m;
  std::string why;
  const std::optional<KnotPlace> p = KnotPoint(points, t, knot, options, &m, &why);
  if (!p) return why;
  const calib::Camera& cam = rig.cameras[rig_index[camera]];
  const auto q = SeenAt(cam, *p, options, &why);
  if (!q) return why;
  m.camera = camera;
  m.expected_px = *q;
  const double time_s = options.target.empty() ? 0.0 : labels.frame_index[t] / options.target.fps;
  if (TargetHides(options.target, cam.Center(), p->position, time_s, options.target_grow_m))
    return "the target hides its point (" + MissingReason(m, labels.cameras) + ")";
  return "";
}

std::string MissingReason(const MissingKnot& missing, const std::vector<std::string>& cameras,
                          const std::vector<int>& frame_index) {
  char where[96];
  std::snprintf(where, sizeof where, "(%.1f, %.1f)", missing.expected_px.x(),
                missing.expected_px.y());
  std::string seen;
  if (!missing.seen_in.empty()) {
    seen = "seen in " + Names(missing.seen_in, cameras);
    if (!missing.under_review.empty())
      seen += " (" + Names(missing.under_review, cameras) + " under review)";
  }
  std::string rows;
  for (int s : missing.rows) {
    const int frame = s >= 0 && s < static_cast<int>(frame_index.size()) ? frame_index[s] : s;
    rows += (rows.empty() ? "" : " and ") + std::to_string(frame);
  }
  switch (missing.basis) {
    case MissingBasis::kCameras: return "no label; " + seen + "; expected near " + where;
    case MissingBasis::kNeighbours:
      return seen.empty() ? std::string("no label; its grid neighbours put it near ") + where
                          : "no label; " + seen +
                                ", at the depth its grid neighbours give; expected near " + where;
    case MissingBasis::kMotion:
      return seen.empty() ? "no label; its points in frames " + rows + " put it near " + where
                          : "no label; " + seen + ", at the depth its points in frames " + rows +
                                " give; expected near " + where;
  }
  return "";
}

}  // namespace netlab::recon
