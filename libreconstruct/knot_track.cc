#include "libreconstruct/knot_track.h"

#include <algorithm>
#include <cmath>
#include <map>

#include <opencv2/imgproc.hpp>
#include <opencv2/video/tracking.hpp>

namespace netlab::recon {
namespace {

cv::Mat Grey8(const cv::Mat& image) {
  cv::Mat grey = image;
  if (image.channels() == 3) cv::cvtColor(image, grey, cv::COLOR_BGR2GRAY);
  if (grey.depth() != CV_8U) {
    double max = 0.0;
    cv::minMaxLoc(grey, nullptr, &max);
    grey.convertTo(grey, CV_8U, max > 0 ? 255.0 / max : 1.0);
  }
  return grey;
}

double Median(std::vector<double> v) {
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

}  // namespace

std::vector<TrackedKnot> TrackKnots(const cv::Mat& from, const cv::Mat& to,
                                    const std::vector<std::pair<int, Eigen::Vector2d>>& knots,
                                    int rows, int cols, const TrackOptions& options) {
  std::vector<TrackedKnot> out(knots.size());
  if (knots.empty()) return out;
  // Thin yarns vanish in the flow's coarse pyramid levels: blurred first, they stay visible.
  cv::Mat a, b;
  cv::GaussianBlur(Grey8(from), a, cv::Size(), options.flow_blur_px);
  cv::GaussianBlur(Grey8(to), b, cv::Size(), options.flow_blur_px);
  std::vector<cv::Point2f> p0, p1, back;
  for (const auto& [k, px] : knots) p0.emplace_back(static_cast<float>(px.x()), static_cast<float>(px.y()));
  std::vector<uchar> ok_forward, ok_back;
  std::vector<float> err;
  const cv::Size window(options.window_px, options.window_px);
  const cv::TermCriteria stop(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 30, 0.001);
  cv::calcOpticalFlowPyrLK(a, b, p0, p1, ok_forward, err, window, options.pyramid_levels, stop);
  cv::calcOpticalFlowPyrLK(b, a, p1, back, ok_back, err, window, options.pyramid_levels, stop);
  // Flow per knot, where trusted.
  std::map<int, Eigen::Vector2d> motion;
  std::vector<bool> trusted(knots.size(), false);
  for (size_t i = 0; i < knots.size(); ++i) {
    const double fb = std::hypot(back[i].x - p0[i].x, back[i].y - p0[i].y);
    trusted[i] = ok_forward[i] && ok_back[i] && fb <= options.max_fb_error_px;
    if (trusted[i])
      motion[knots[i].first] = Eigen::Vector2d(p1[i].x, p1[i].y) - knots[i].second;
  }
  for (size_t i = 0; i < knots.size(); ++i) {
    const auto& [k, px] = knots[i];
    TrackedKnot& t = out[i];
    t.knot = k;
    const int r = k / cols, c = k % cols;
    const int degree = (r > 0) + (r + 1 < rows) + (c > 0) + (c + 1 < cols);
    Eigen::Vector2d predicted;
    if (trusted[i]) {
      predicted = Eigen::Vector2d(p1[i].x, p1[i].y);
    } else {
      std::vector<double> dx, dy;
      for (int n : {k - 1, k + 1, k - cols, k + cols}) {
        if (n < 0 || n >= rows * cols || (std::abs(n - k) == 1 && n / cols != r)) continue;
        const auto it = motion.find(n);
        if (it == motion.end()) continue;
        dx.push_back(it->second.x());
        dy.push_back(it->second.y());
      }
      if (dx.empty()) {
        t.px = px;
        t.why = "no trusted flow for the knot or its neighbours";
        continue;
      }
      predicted = px + Eigen::Vector2d(Median(dx), Median(dy));
      t.why = "flow lost (forward-backward check); predicted from the neighbours' motion";
    }
    // The knot detector's brush at the prediction, snap radius wide.
    const std::vector<Junction> near =
        FindNode(to, predicted, options.snap_radius_px, options.detector).candidates;
    t.px = predicted;
    if (near.empty()) {
      if (t.why.empty()) t.why = "no junction within " + std::to_string(options.snap_radius_px) + " px of the flow";
      continue;
    }
    if (near.size() > 1) {
      t.why = std::to_string(near.size()) + " junctions within the snap radius";
      continue;
    }
    t.px = near[0].px;
    t.confidence = near[0].confidence;
    if (near[0].branches != degree) {
      t.why = "the junction there has " + std::to_string(near[0].branches) + " yarns, the knot " +
              std::to_string(degree);
      continue;
    }
    if (trusted[i]) t.accepted = true;
  }
  // Two knots on one junction: neither is trusted.
  for (size_t i = 0; i < out.size(); ++i)
    for (size_t j = i + 1; j < out.size(); ++j)
      if ((out[i].px - out[j].px).norm() < options.snap_radius_px) {
        for (TrackedKnot* t : {&out[i], &out[j]}) {
          if (t->accepted) t->why = "another knot tracked onto the same place";
          t->accepted = false;
        }
      }
  return out;
}

}  // namespace netlab::recon
