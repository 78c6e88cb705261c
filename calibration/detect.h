#pragma once
// Finding a target's points in an image, with sub-pixel refinement.

#include <Eigen/Core>
#include <opencv2/core.hpp>
#include <vector>

#include "calibration/target.h"

namespace netlab::calib {

// Points of one face found in one image: ids (BoardPattern's) and pixels (OpenCV convention).
struct PatternDetection {
  std::vector<int> ids;
  std::vector<Eigen::Vector2d> pixels;
  bool empty() const { return ids.empty(); }
};

struct DetectionOptions {
  // Chessboards are first found on a copy no larger than this (px), then refined at full
  // resolution: finding a board in a 2048 px image costs seconds, refining it milliseconds.
  int coarse_max_size = 1024;
  // A ChArUco view counts only with at least this many corners (fewer do not constrain a pose).
  int min_charuco_corners = 6;
};

// Finds `pattern` in an 8-bit grey image; empty when not found. Chessboard corners come in the
// canonical order of target.h (handedness and the odd x even colour test resolve the ambiguity of
// OpenCV's ordering). Marker patterns return the corners of every known marker found.
PatternDetection DetectPattern(const cv::Mat& gray, const BoardPattern& pattern,
                               const DetectionOptions& options = {});

// An 8-bit grey copy of an image of any depth and channel count (16-bit scaled by its maximum).
cv::Mat ToGray8(const cv::Mat& image);

}  // namespace netlab::calib
