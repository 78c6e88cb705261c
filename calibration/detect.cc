#include "calibration/detect.h"

#include <algorithm>
#include <cmath>
#include <opencv2/aruco.hpp>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

namespace netlab::calib {
namespace {

// Mean intensity of a small disc at p (clipped to the image).
double MeanAround(const cv::Mat& gray, const Eigen::Vector2d& p, double radius) {
  const int r = std::max(1, static_cast<int>(radius));
  const int x0 = std::clamp(static_cast<int>(std::lround(p.x())) - r, 0, gray.cols - 1);
  const int x1 = std::clamp(static_cast<int>(std::lround(p.x())) + r, 0, gray.cols - 1);
  const int y0 = std::clamp(static_cast<int>(std::lround(p.y())) - r, 0, gray.rows - 1);
  const int y1 = std::clamp(static_cast<int>(std::lround(p.y())) + r, 0, gray.rows - 1);
  return cv::mean(gray(cv::Rect(x0, y0, x1 - x0 + 1, y1 - y0 + 1)))[0];
}

PatternDetection DetectChessboard(const cv::Mat& gray, const BoardPattern& pattern,
                                  const DetectionOptions& options) {
  const cv::Size size(pattern.cols, pattern.rows);
  // Coarse detection on a downscaled copy.
  const double scale =
      std::min(1.0, static_cast<double>(options.coarse_max_size) / std::max(gray.cols, gray.rows));
  cv::Mat small = gray;
  if (scale < 1.0) cv::resize(gray, small, cv::Size(), scale, scale, cv::INTER_AREA);
  std::vector<cv::Point2f> corners;
  // The sector-based detector: OpenCV's classic findChessboardCorners searched for minutes on a
  // plain noisy background and did not return at all (> 200 s) when asked for 7x6 corners in an
  // image of a 9x6 board; this one answers both in ~0.2 s at 1024 px.
  if (!cv::findChessboardCornersSB(small, size, corners, cv::CALIB_CB_NORMALIZE_IMAGE)) return {};
  for (cv::Point2f& c : corners) c /= static_cast<float>(scale);

  // Sub-pixel refinement at full resolution, window ~ a third of the smallest square.
  double spacing = 1e9;
  for (int r = 0; r < pattern.rows; ++r)
    for (int c = 0; c + 1 < pattern.cols; ++c)
      spacing = std::min<double>(
          spacing, cv::norm(corners[r * pattern.cols + c + 1] - corners[r * pattern.cols + c]));
  const int window = std::clamp(static_cast<int>(spacing / 3.0), 2, 15);
  cv::cornerSubPix(gray, corners, cv::Size(window, window), cv::Size(-1, -1),
                   cv::TermCriteria(cv::TermCriteria::EPS + cv::TermCriteria::COUNT, 50, 1e-4));

  // Canonical order. Handedness first: x (along a row) then y (to the next row) must turn like
  // the print seen from the front (clockwise in an image with y down).
  const int cols = pattern.cols, rows = pattern.rows, n = cols * rows;
  auto at = [&](int i) { return Eigen::Vector2d(corners[i].x, corners[i].y); };
  const Eigen::Vector2d dx = at(1) - at(0), dy = at(cols) - at(0);
  if (dx.x() * dy.y() - dx.y() * dy.x() < 0.0) {
    std::vector<cv::Point2f> flipped(n);
    for (int r = 0; r < rows; ++r)
      for (int c = 0; c < cols; ++c) flipped[r * cols + c] = corners[(rows - 1 - r) * cols + c];
    corners.swap(flipped);
  }
  // Then colour: the inner square at corner 0 is black, the one at the last corner white.
  const Eigen::Vector2d first = 0.25 * (at(0) + at(1) + at(cols) + at(cols + 1));
  const Eigen::Vector2d last = 0.25 * (at(n - 1) + at(n - 2) + at(n - 1 - cols) + at(n - 2 - cols));
  const double radius = 0.2 * spacing;
  if (MeanAround(gray, first, radius) > MeanAround(gray, last, radius))
    std::reverse(corners.begin(), corners.end());

  PatternDetection d;
  for (int i = 0; i < n; ++i) {
    d.ids.push_back(i);
    d.pixels.emplace_back(corners[i].x, corners[i].y);
  }
  return d;
}

PatternDetection DetectCharuco(const cv::Mat& gray, const BoardPattern& pattern,
                               const DetectionOptions& options) {
  std::vector<std::vector<cv::Point2f>> marker_corners;
  std::vector<int> marker_ids;
  cv::Ptr<cv::aruco::DetectorParameters> params = cv::aruco::DetectorParameters::create();
  cv::aruco::detectMarkers(gray, pattern.aruco_dictionary, marker_corners, marker_ids, params);
  if (marker_ids.empty()) return {};
  std::vector<cv::Point2f> corners;
  std::vector<int> ids;
  // Interpolated from the markers by local homographies. OpenCV 4.6 returns these corners half a
  // pixel down and right of where its own pixel convention puts them (measured on rendered
  // boards: +0.50 px in both axes, where chessboard corners are unbiased to 0.01 px), so they are
  // refined again with cornerSubPix, in a window that stays inside the white gap between the
  // corner and the nearest marker, (square - marker) / 2.
  cv::aruco::interpolateCornersCharuco(marker_corners, marker_ids, gray, pattern.charuco, corners,
                                       ids);
  if (static_cast<int>(ids.size()) < options.min_charuco_corners) return {};
  double marker_side = 1e9;
  for (const auto& m : marker_corners)
    marker_side = std::min<double>(marker_side, cv::norm(m[1] - m[0]));
  const double square_px = marker_side * pattern.square / pattern.marker;
  const double gap_px = 0.5 * square_px * (1.0 - pattern.marker / pattern.square);
  const int window = std::clamp(static_cast<int>(0.8 * gap_px), 2, 15);
  cv::cornerSubPix(gray, corners, cv::Size(window, window), cv::Size(-1, -1),
                   cv::TermCriteria(cv::TermCriteria::EPS + cv::TermCriteria::COUNT, 50, 1e-4));
  PatternDetection d;
  for (size_t i = 0; i < ids.size(); ++i) {
    d.ids.push_back(ids[i]);
    d.pixels.emplace_back(corners[i].x, corners[i].y);
  }
  return d;
}

PatternDetection DetectMarkerCorners(const cv::Mat& gray, const BoardPattern& pattern) {
  std::vector<std::vector<cv::Point2f>> marker_corners;
  std::vector<int> marker_ids;
  cv::Ptr<cv::aruco::DetectorParameters> params = cv::aruco::DetectorParameters::create();
  params->cornerRefinementMethod = cv::aruco::CORNER_REFINE_SUBPIX;
  cv::aruco::detectMarkers(gray, pattern.aruco_dictionary, marker_corners, marker_ids, params);
  PatternDetection d;
  for (size_t m = 0; m < marker_ids.size(); ++m) {
    const int id = marker_ids[m];
    if (4 * id + 3 >= static_cast<int>(pattern.points.size()) ||
        !pattern.points[4 * id].allFinite())
      continue;  // a marker that is not on the map
    for (int k = 0; k < 4; ++k) {
      d.ids.push_back(4 * id + k);
      d.pixels.emplace_back(marker_corners[m][k].x, marker_corners[m][k].y);
    }
  }
  return d;
}

}  // namespace

cv::Mat ToGray8(const cv::Mat& image) {
  cv::Mat gray = image;
  if (gray.channels() == 3) cv::cvtColor(gray, gray, cv::COLOR_BGR2GRAY);
  if (gray.channels() == 4) cv::cvtColor(gray, gray, cv::COLOR_BGRA2GRAY);
  if (gray.depth() != CV_8U) {
    double max_value = 0.0;
    cv::minMaxLoc(gray, nullptr, &max_value);
    gray.convertTo(gray, CV_8U, max_value > 0.0 ? 255.0 / max_value : 1.0);
  }
  return gray;
}

PatternDetection DetectPattern(const cv::Mat& gray, const BoardPattern& pattern,
                               const DetectionOptions& options) {
  switch (pattern.type) {
    case PatternType::kChessboard: return DetectChessboard(gray, pattern, options);
    case PatternType::kCharuco: return DetectCharuco(gray, pattern, options);
    case PatternType::kMarkers: return DetectMarkerCorners(gray, pattern);
  }
  return {};
}

}  // namespace netlab::calib
