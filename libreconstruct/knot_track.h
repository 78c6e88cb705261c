#pragma once
// Tracking labeled knots from one frame to the next (or the previous) of one camera.
//
// Pyramidal Lucas-Kanade optical flow on the blurred grey image, forwards and back: a knot whose
// forward-backward error exceeds max_fb_error_px has no trusted flow. Every knot is then re-snapped
// with the knot detector at its predicted position (the flow's, or for a knot without one the
// median motion of its grid neighbours that have one: an occluded knot moves with the net). A
// knot is accepted only when the flow is trusted, a junction of the knot's degree (2 corner,
// 3 edge, 4 inner) is within snap_radius_px of the flow, and no other knot's result lies within
// that radius; otherwise it needs review, with the reason, at the best position there is.

#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "libreconstruct/knot_detect.h"

namespace netlab::recon {

struct TrackOptions {
  double max_fb_error_px = 0.5;
  double snap_radius_px = 3.0;
  int window_px = 31;
  int pyramid_levels = 4;
  double flow_blur_px = 2.5;  // Gaussian blur of the images for the flow (thin yarns)
  KnotDetectorOptions detector;
};

struct TrackedKnot {
  int knot = 0;                         // row * cols + col
  Eigen::Vector2d px = Eigen::Vector2d::Zero();  // in the next frame
  bool accepted = false;
  double confidence = 0.0;
  std::string why;                      // when not accepted
};

// `knots`: (knot index, position in `from`). Images: the same camera's consecutive frames, BGR or
// grey, 8 or 16 bit.
std::vector<TrackedKnot> TrackKnots(const cv::Mat& from, const cv::Mat& to,
                                    const std::vector<std::pair<int, Eigen::Vector2d>>& knots,
                                    int rows, int cols, const TrackOptions& options = {});

}  // namespace netlab::recon
