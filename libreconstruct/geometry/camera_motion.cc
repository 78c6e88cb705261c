#include "libreconstruct/geometry/camera_motion.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include "libreconstruct/geometry/camera_offsets.h"
#include "libreconstruct/geometry/triangulation.h"

namespace netlab::recon {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

double Median(std::vector<double> v) {
  const size_t n = v.size();
  std::nth_element(v.begin(), v.begin() + n / 2, v.end());
  const double upper = v[n / 2];
  if (n % 2 == 1) return upper;
  return 0.5 * (upper + *std::max_element(v.begin(), v.begin() + n / 2));
}

// The median of 2-D residuals (each axis) and its standard deviation, 1.25 x 1.4826 MAD /
// sqrt(n) (the larger axis).
void MedianShift(const std::vector<Eigen::Vector2d>& r, Eigen::Vector2d* median, double* sigma) {
  double s = 0.0;
  for (int axis = 0; axis < 2; ++axis) {
    std::vector<double> v;
    for (const Eigen::Vector2d& p : r) v.push_back(p[axis]);
    const double m = Median(v);
    for (double& x : v) x = std::abs(x - m);
    (*median)[axis] = m;
    s = std::max(s, 1.25 * 1.4826 * Median(v) / std::sqrt(static_cast<double>(r.size())));
  }
  *sigma = s;
}

// The shifts of rig camera c in every frame against the other cameras but those `excluded`.
void MeasureShifts(const calib::Rig& rig, const LabelSet& labels, const std::vector<int>& label_of,
                   const std::vector<std::vector<uint8_t>>& usable, const TriangulationOptions& tri,
                   const std::vector<bool>& excluded, int c, const CameraMotionOptions& motion,
                   CameraMotion* out) {
  const int knots = labels.knots();
  const int lc = label_of[c];
  out->frame = labels.frame_index;
  out->shift_px.assign(labels.frames(), Eigen::Vector2d::Constant(kNaN));
  out->sigma_px.assign(labels.frames(), kNaN);
  out->knots.assign(labels.frames(), 0);
  if (lc < 0) return;
  for (int t = 0; t < labels.frames(); ++t) {
    std::vector<Eigen::Vector2d> residuals;
    for (int k = 0; k < knots; ++k) {
      const size_t i = static_cast<size_t>(t) * knots + k;
      if (!usable[lc][i]) continue;
      std::vector<Observation> others;
      for (int o = 0; o < static_cast<int>(rig.cameras.size()); ++o) {
        const int lo = label_of[o];
        if (o == c || lo < 0 || excluded[o] || !usable[lo][i]) continue;
        others.push_back({o, labels.labels[lo][i].px});
      }
      if (others.size() < 2) continue;
      const std::optional<ProjectedPoint> p = ProjectAgreeingViews(rig, c, others, tri);
      if (p) residuals.push_back(labels.labels[lc][i].px - p->px);
    }
    out->knots[t] = static_cast<int>(residuals.size());
    if (out->knots[t] >= motion.min_knots)
      MedianShift(residuals, &out->shift_px[t], &out->sigma_px[t]);
  }
}

// The place at the start and the frames departing from it (CameraMotion's fields).
void JudgeShifts(const CameraMotionOptions& motion, CameraMotion* m) {
  m->moved.clear();
  m->largest_departure_px = 0.0;
  m->largest_departure_frame = -1;
  std::vector<int> rows;
  for (size_t t = 0; t < m->frame.size(); ++t)
    if (std::isfinite(m->sigma_px[t])) rows.push_back(static_cast<int>(t));
  const int start_rows = std::max(5, static_cast<int>(rows.size()) / 10);
  m->measured = static_cast<int>(rows.size()) >= start_rows;
  if (!m->measured) {
    m->why = "fewer than " + std::to_string(start_rows) + " frames with " +
             std::to_string(motion.min_knots) +
             " knots it labels that two other cameras triangulate";
    return;
  }
  std::vector<Eigen::Vector2d> start;
  for (int i = 0; i < start_rows; ++i) start.push_back(m->shift_px[rows[i]]);
  MedianShift(start, &m->start_px, &m->start_sigma_px);
  // Runs of departing frames in a row (among the measured ones), at least min_frames long.
  int run_first = -1, run_length = 0, previous = -1;
  auto close_run = [&]() {
    if (run_first >= 0 && run_length >= motion.min_frames)
      m->moved.emplace_back(m->frame[run_first], m->frame[previous]);
    run_first = -1;
    run_length = 0;
  };
  for (const int t : rows) {
    const double departure = (m->shift_px[t] - m->start_px).norm();
    const double sigma = std::hypot(m->sigma_px[t], m->start_sigma_px);
    const bool departs = departure > motion.min_departure_px && departure > motion.sigmas * sigma;
    if (departs) {
      if (run_first < 0) run_first = t;
      ++run_length;
      if (departure > m->largest_departure_px) {
        m->largest_departure_px = departure;
        m->largest_departure_frame = m->frame[t];
      }
    } else {
      close_run();
    }
    previous = t;
  }
  close_run();
  if (m->moved.empty()) m->largest_departure_frame = -1, m->largest_departure_px = 0.0;
}

}  // namespace

std::vector<CameraMotion> DetectCameraMotion(const calib::Rig& rig, const LabelSet& labels,
                                             const SequenceOptions& options,
                                             const CameraMotionOptions& motion) {
  const int cameras = static_cast<int>(rig.cameras.size());
  const std::vector<int> label_of = LabelCameraOfRigCamera(rig, labels);
  // Every label but the projected ones, those under review too: a camera that moved has its
  // labels put under review by the labeling's epipolar check (on the twin with cam2 jumping 1.5
  // mm, all of them after the jump), and the median does not heed the few wrong ones.
  SequenceOptions all = options;
  all.use_unreviewed = true;
  const std::vector<std::vector<uint8_t>> usable = UsableLabels(labels, all);
  const TriangulationOptions tri = options.sigma_px > 0.0 && options.auto_threshold
                                       ? TriangulationForNoise(options, options.sigma_px)
                                       : options.triangulation;
  std::vector<CameraMotion> result(cameras);
  std::vector<bool> named(cameras, false);  // judged moved, out of the others' points
  for (int c = 0; c < cameras; ++c) result[c].camera = rig.cameras[c].name;
  for (int round = 0; round < cameras; ++round) {
    int farthest = -1;
    for (int c = 0; c < cameras; ++c) {
      if (named[c]) continue;
      CameraMotion& m = result[c];
      MeasureShifts(rig, labels, label_of, usable, tri, named, c, motion, &m);
      if (label_of[c] < 0) {
        m.why = "no labels of this camera";
        continue;
      }
      JudgeShifts(motion, &m);
      if (!m.moved.empty() &&
          (farthest < 0 || m.largest_departure_px > result[farthest].largest_departure_px))
        farthest = c;
    }
    if (farthest < 0) break;
    named[farthest] = true;
  }
  return result;
}

std::vector<std::string> CameraMotionSentences(const std::vector<CameraMotion>& cameras) {
  std::vector<std::string> sentences;
  for (const CameraMotion& m : cameras) {
    if (m.moved.empty()) continue;
    std::string frames;
    for (const auto& [first, last] : m.moved) {
      if (!frames.empty()) frames += ", ";
      frames += first == last ? std::to_string(first)
                              : std::to_string(first) + "-" + std::to_string(last);
    }
    char text[400];
    std::snprintf(text, sizeof text,
                  "%s moved in frame%s %s: its labels up to %.2f px (frame %d) from where they "
                  "sat at the start against the other cameras' points; recalibrate it, or adjust "
                  "the rig (--ba rig) over those frames",
                  m.camera.c_str(),
                  m.moved.size() == 1 && m.moved[0].first == m.moved[0].second ? "" : "s",
                  frames.c_str(), m.largest_departure_px, m.largest_departure_frame);
    sentences.push_back(text);
  }
  return sentences;
}

}  // namespace netlab::recon
