#include "libreconstruct/geometry/camera_offsets.h"

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <functional>
#include <limits>
#include <mutex>
#include <sstream>
#include <thread>

#include "common/yaml_util.h"
#include "libreconstruct/geometry/triangulation.h"

namespace netlab::recon {
namespace {

std::string Format(const char* format, double value) {
  char text[64];
  std::snprintf(text, sizeof text, format, value);
  return text;
}

// Runs body(t) for t in [0, n) on `threads` threads.
void ForEachFrame(int n, int threads, const std::function<void(int)>& body) {
  std::atomic<int> next{0};
  auto work = [&] {
    for (int t = next++; t < n; t = next++) body(t);
  };
  std::vector<std::thread> pool;
  for (int i = 1; i < std::max(1, threads); ++i) pool.emplace_back(work);
  work();
  for (auto& th : pool) th.join();
}

// The sums of one camera's Gauss-Newton step in its offset.
struct OffsetSums {
  double h = 0.0, g = 0.0, ss = 0.0, motion2 = 0.0;
  int n = 0;
  void Add(const OffsetSums& o) {
    h += o.h, g += o.g, ss += o.ss, motion2 += o.motion2;
    n += o.n;
  }
};

// The knots are split into this many groups (knot k in group k % kKnotGroups) for the
// jackknife of the offsets' sigma.
constexpr int kKnotGroups = 10;

}  // namespace

std::vector<double> OffsetEstimate::Applicable() const {
  std::vector<double> out;
  for (const CameraOffset& c : cameras) out.push_back(c.determined ? c.offset_frames : 0.0);
  return out;
}

FrameTimes FrameTimesFromTimestamps(const std::vector<int>& frame_index, double fps,
                                    const std::vector<std::string>& cameras,
                                    const std::vector<std::map<int, double>>& timestamps,
                                    const std::vector<std::string>& where) {
  FrameTimes out;
  const size_t n = frame_index.size();
  out.time_s.assign(n, 0.0);
  out.spread_s.assign(n, 0.0);
  std::vector<size_t> with;
  for (size_t c = 0; c < timestamps.size(); ++c)
    if (!timestamps[c].empty()) with.push_back(c);
  if (with.empty()) {
    for (size_t t = 0; t < n; ++t) out.time_s[t] = frame_index[t] / fps;
    return out;
  }
  for (size_t c : with) {
    out.cameras.push_back(cameras[c]);
    const std::map<int, double>& times = timestamps[c];
    std::vector<int> missing;
    for (int f : frame_index)
      if (!times.count(f)) missing.push_back(f);
    if (!missing.empty()) {
      std::ostringstream os;
      os << where[c] << ": camera " << cameras[c] << "'s timestamps have " << times.size()
         << " frames (" << times.begin()->first << ".." << times.rbegin()->first << ") and lack "
         << missing.size() << " of the " << n << " labeled frames (frame " << missing.front()
         << (missing.size() > 1 ? " and more" : "") << ")";
      throw InputError(os.str());
    }
    for (size_t t = 1; t < n; ++t) {
      const double a = times.at(frame_index[t - 1]), b = times.at(frame_index[t]);
      if (!(b > a)) {
        std::ostringstream os;
        os.precision(12);
        os << where[c] << ": camera " << cameras[c] << "'s timestamps go backwards: frame "
           << frame_index[t - 1] << " at " << a << " s, frame " << frame_index[t] << " at " << b
           << " s";
        throw InputError(os.str());
      }
    }
  }
  for (size_t t = 0; t < n; ++t) {
    double sum = 0.0, lo = 0.0, hi = 0.0;
    size_t lo_c = with[0], hi_c = with[0];
    for (size_t i = 0; i < with.size(); ++i) {
      const double v = timestamps[with[i]].at(frame_index[t]);
      sum += v;
      if (i == 0 || v < lo) lo = v, lo_c = with[i];
      if (i == 0 || v > hi) hi = v, hi_c = with[i];
    }
    if (hi - lo > 1.0 / fps) {
      std::ostringstream os;
      os.precision(12);
      os << where[hi_c] << ": the cameras' timestamps of frame " << frame_index[t]
         << " disagree by " << Format("%.3g", (hi - lo) * fps) << " frames (" << cameras[lo_c]
         << " " << lo << " s, " << cameras[hi_c] << " " << hi << " s), more than one frame at "
         << fps << " fps: not the same frame";
      throw InputError(os.str());
    }
    out.time_s[t] = sum / static_cast<double>(with.size());
    out.spread_s[t] = hi - lo;
  }
  return out;
}

std::vector<std::vector<uint8_t>> UsableLabels(const LabelSet& labels,
                                               const SequenceOptions& options) {
  std::vector<std::vector<uint8_t>> usable(labels.cameras.size());
  for (size_t c = 0; c < labels.cameras.size(); ++c) {
    usable[c].assign(labels.labels[c].size(), 0);
    for (size_t i = 0; i < labels.labels[c].size(); ++i) {
      const Label& l = labels.labels[c][i];
      usable[c][i] = l.present() && l.source != LabelSource::kProjected &&
                     (l.state != LabelState::kNeedsReview || options.use_unreviewed);
    }
  }
  return usable;
}

bool LabelAtFrameTime(const LabelSet& labels, int c, int t, int k, double offset,
                      const std::vector<uint8_t>& usable, Eigen::Vector2d* px,
                      Eigen::Vector2d* velocity) {
  const int frames = labels.frames(), knots = labels.knots();
  auto at = [&](int row, int frame, Eigen::Vector2d* p) {
    if (row < 0 || row >= frames || labels.frame_index[row] != frame) return false;
    const size_t i = static_cast<size_t>(row) * knots + k;
    if (!usable[i]) return false;
    *p = labels.labels[c][i].px;
    return true;
  };
  const int f = labels.frame_index[t];
  Eigen::Vector2d p0, pm, pp;
  if (!at(t, f, &p0)) return false;
  const bool before = at(t - 1, f - 1, &pm), after = at(t + 1, f + 1, &pp);
  // The label's track in the camera's own frame numbers s (s = 0: this label, taken at frame
  // time f + offset), read at s = -offset: the frame time.
  const double s = -offset;
  Eigen::Vector2d d1, d2 = Eigen::Vector2d::Zero();
  if (before && after) {
    d1 = 0.5 * (pp - pm);
    d2 = pp - 2.0 * p0 + pm;
  } else if (after) {
    d1 = pp - p0;
  } else if (before) {
    d1 = p0 - pm;
  } else {
    return false;
  }
  *px = p0 + s * d1 + 0.5 * s * s * d2;
  if (velocity) *velocity = d1 + s * d2;
  return true;
}

std::vector<int> LabelCameraOfRigCamera(const calib::Rig& rig, const LabelSet& labels) {
  std::vector<int> label_of(rig.cameras.size(), -1);
  for (size_t lc = 0; lc < labels.cameras.size(); ++lc) {
    const int c = rig.Find(labels.cameras[lc]);
    if (c < 0)
      throw InputError("the labels use camera '" + labels.cameras[lc] +
                       "', which the rig does not have");
    label_of[c] = static_cast<int>(lc);
  }
  return label_of;
}

OffsetEstimate EstimateCameraOffsets(const calib::Rig& rig, const LabelSet& labels,
                                     const SequenceOptions& options,
                                     const OffsetOptions& offset_options) {
  const int cameras = static_cast<int>(rig.cameras.size());
  const int frames = labels.frames(), knots = labels.knots();
  const std::vector<int> label_of = LabelCameraOfRigCamera(rig, labels);
  const std::vector<std::vector<uint8_t>> usable = UsableLabels(labels, options);
  OffsetEstimate estimate;
  estimate.cameras.resize(cameras);
  int reference = -1;
  for (int c = 0; c < cameras; ++c) {
    estimate.cameras[c].camera = rig.cameras[c].name;
    if (label_of[c] < 0) {
      estimate.cameras[c].why = "no labels of this camera";
    } else if (reference < 0) {
      reference = c;
      estimate.cameras[c].determined = true;
      estimate.cameras[c].why = "the reference";
    }
  }
  const TriangulationOptions tri = options.sigma_px > 0.0 && options.auto_threshold
                                       ? TriangulationForNoise(options, options.sigma_px)
                                       : options.triangulation;

  // The sums of camera c's step at the offsets `at`: every knot-frame it labels, against the
  // point the other cameras (their labels moved by their offsets) put there; the knots of group
  // `left_out` (-1: none) are not used.
  auto sums_of = [&](int c, const std::vector<double>& at, int left_out) {
    std::vector<OffsetSums> per_frame(frames);
    const int lc = label_of[c];
    ForEachFrame(frames, options.threads, [&](int t) {
      OffsetSums& s = per_frame[t];
      for (int k = 0; k < knots; ++k) {
        if (k % kKnotGroups == left_out) continue;
        Eigen::Vector2d px, u;
        if (!LabelAtFrameTime(labels, lc, t, k, at[c], usable[lc], &px, &u)) continue;
        std::vector<Observation> others;
        for (int o = 0; o < cameras; ++o) {
          if (o == c || label_of[o] < 0) continue;
          const int lo = label_of[o];
          const size_t i = static_cast<size_t>(t) * knots + k;
          if (!usable[lo][i]) continue;
          Eigen::Vector2d q = labels.labels[lo][i].px;
          if (at[o] != 0.0 && !LabelAtFrameTime(labels, lo, t, k, at[o], usable[lo], &q)) continue;
          others.push_back({o, q});
        }
        if (others.size() < 2) continue;
        const PointEstimate point = TriangulatePoint(rig, others, tri);
        const auto projected = ProjectEstimate(rig, c, point);
        if (!projected) continue;
        const Eigen::Vector2d r = projected->px - px;
        const Eigen::Matrix2d w =
            (Eigen::Matrix2d::Identity() + projected->unit_covariance).inverse();
        // An outlier is beyond the threshold even at the best offset within a frame either way.
        const double d2 = r.dot(w * r);
        const double gate = tri.outlier_threshold_px + u.norm();
        if (!std::isfinite(d2) || d2 > gate * gate) continue;
        // r(offset + step) = r + step u: the label moves back along its track.
        s.h += u.dot(w * u);
        s.g += u.dot(w * r);
        s.ss += d2;
        // The motion as the labels show it (at the frame's own time, not at the offset: a track
        // of noise extrapolated by a wrong offset would look like motion).
        Eigen::Vector2d at_label, motion;
        LabelAtFrameTime(labels, lc, t, k, 0.0, usable[lc], &at_label, &motion);
        s.motion2 += motion.squaredNorm();
        ++s.n;
      }
    });
    OffsetSums total;
    for (const OffsetSums& s : per_frame) total.Add(s);
    return total;
  };

  // Gauss-Newton on each camera in turn from `offset` until no offset changes by the tolerance;
  // `last`, when given, gets each camera's sums of the last sweep. The number of sweeps.
  auto solve = [&](std::vector<double>& offset, int left_out, std::vector<OffsetSums>* last) {
    int sweeps = 0;
    while (sweeps < offset_options.max_sweeps) {
      ++sweeps;
      double change = 0.0;
      for (int c = 0; c < cameras; ++c) {
        if (c == reference || label_of[c] < 0) continue;
        const OffsetSums s = sums_of(c, offset, left_out);
        if (last) (*last)[c] = s;
        if (s.n < offset_options.min_observations || !(s.h > 0.0)) continue;
        const double step = -s.g / s.h;
        offset[c] += step;
        change = std::max(change, std::abs(step));
      }
      if (change < offset_options.tolerance_frames) break;
    }
    return sweeps;
  };

  std::vector<double> offset(cameras, 0.0);
  std::vector<OffsetSums> last(cameras);
  estimate.sweeps = solve(offset, -1, &last);

  // The delete-a-group jackknife over the knots: the whole estimate again with each group of
  // knots left out (from the full one), the spread of those estimates scaled by
  // (groups - 1) / groups. A knot's label errors that persist from frame to frame (a junction
  // misplaced the same way while it looks the same), in this camera or in the cameras that place
  // the point, do not average out over the frames; the scatter of the residuals alone then
  // understates the doubt (3-6 fold on the rendered shots of docs/triangulation.md).
  const int groups = std::min(knots, kKnotGroups);
  std::vector<std::vector<double>> left_out_offsets;
  if (groups >= 2)
    for (int g = 0; g < groups; ++g) {
      std::vector<double> o = offset;
      solve(o, g, nullptr);
      left_out_offsets.push_back(o);
    }
  auto jackknife_sigma = [&](int c) {
    const double m = static_cast<double>(left_out_offsets.size());
    if (m < 2) return 0.0;
    double mean = 0.0, spread = 0.0;
    for (const auto& o : left_out_offsets) mean += o[c] / m;
    for (const auto& o : left_out_offsets) spread += (o[c] - mean) * (o[c] - mean);
    return std::sqrt((m - 1.0) / m * spread);
  };

  for (int c = 0; c < cameras; ++c) {
    if (c == reference || label_of[c] < 0) continue;
    CameraOffset& out = estimate.cameras[c];
    out.offset_frames = std::numeric_limits<double>::quiet_NaN();  // until determined
    const OffsetSums& s = last[c];
    out.observations = s.n;
    out.motion_px = s.n > 0 ? std::sqrt(s.motion2 / s.n) : 0.0;
    if (s.n < offset_options.min_observations || !(s.h > 0.0)) {
      out.sigma_frames = std::numeric_limits<double>::infinity();
      out.why = "too little to go on: " + std::to_string(s.n) +
                " views of a knot that two other cameras place and that the camera sees in a "
                "neighbouring frame too (at least " +
                std::to_string(offset_options.min_observations) + " needed)";
      continue;
    }
    // The residual scatter at the estimate (per component, weighted) sets the noise.
    const double ss = std::max(0.0, s.ss - s.g * s.g / s.h);
    const double noise2 = s.n > 1 ? ss / (2.0 * s.n - 1.0) : 1.0;
    const double sigma_scatter = std::sqrt(noise2 / s.h);
    out.sigma_frames = std::max(sigma_scatter, jackknife_sigma(c));
    // The motion is read off the labels themselves: where it is not well above their scatter,
    // it is mostly that scatter, and the sigma above understates the doubt.
    const double scatter = std::sqrt(noise2);
    if (!(out.sigma_frames <= offset_options.max_sigma_frames) ||
        !(out.motion_px >= offset_options.min_motion_scatters * scatter)) {
      out.why = "too little motion to determine it: sigma " + Format("%.3f", out.sigma_frames) +
                " frames (bound " + Format("%.3f", offset_options.max_sigma_frames) + "), " +
                std::to_string(s.n) + " views moving " + Format("%.3f", out.motion_px) +
                " px per frame RMS against the labels' scatter of " + Format("%.3f", scatter) +
                " px";
      continue;
    }
    out.determined = true;
    out.offset_frames = offset[c];
  }
  return estimate;
}

}  // namespace netlab::recon
