#pragma once
// Knots in an image of thin coloured threads on a uniform background, and Find Node.
//
// Foreground: F = |I - background| (Euclidean over the colour channels; the background is a
// local median, background_window_px wide, so a target or cabin behind the net does not hide
// the yarns in front of it; solids are masked out, see solid_fraction). Ridges: the Hessian of F smoothed at the thread's scale;
// ridge strength R = max(0, -smallest eigenvalue) (bright lines in F, whatever their colour).
// A knot is where yarns meet: sampled on a circle around a point, R shows one peak per yarn
// leaving it. 3 or 4 peaks (edge, inner knot), or 2 peaks less than straight_angle_deg apart
// (a corner), make a junction; 2 opposite peaks are a yarn passing by. Its sub-pixel position is
// the least-squares intersection of the branch lines, each fitted through its peaks on three
// circles.
//
// Find Node (the circular brush): every junction inside the brush, refined and merged; exactly
// one is returned as found, none or several (with the candidates) are said so — never a guess.

#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

namespace netlab::recon {

struct KnotDetectorOptions {
  double ridge_sigma_px = 1.2;    // Gaussian scale of the Hessian (about the thread's half width)
  double ring_radius_px = 6.0;    // inner circle for the branch count; then 1.5 x and 2 x
  double peak_fraction = 0.25;    // a branch peak exceeds this fraction of the strong ridges
  double min_branch_separation_deg = 25.0;
  double straight_angle_deg = 150.0;  // two branches this far apart are one yarn passing through
  double merge_px = 2.5;          // refined junctions closer than this are one
  int background_window_px = 11;  // median window of the local background (odd, >> a yarn)
  double solid_fraction = 0.3;    // foreground above this fraction of the brightest that stays
  double max_solid_area_px = 3000;  // under an opening, in a blob up to this area: a solid
                                    // (corner mass), where no ridge is taken
};

struct Junction {
  Eigen::Vector2d px = Eigen::Vector2d::Zero();  // OpenCV pixel convention
  int branches = 0;
  std::vector<double> branch_angles_rad;  // image angles (atan2(dy, dx)) of the yarns leaving it
  double fit_rms_px = 0.0;   // RMS distance of px from the branch lines
  double contrast = 0.0;     // weakest branch peak / the peak threshold (> 1)
  double confidence = 0.0;   // 0..1 from contrast and fit
};

class KnotDetector {
 public:
  // Works on `roi` of `image` (CV_8UC3, CV_16UC3 or CV_32FC3 BGR, or one channel); the whole
  // image when roi is empty.
  KnotDetector(const cv::Mat& image, cv::Rect roi = {}, KnotDetectorOptions options = {});

  // The junction at a point (branches counted there, position refined from it); nullopt when
  // the point is not at a junction.
  std::optional<Junction> Examine(const Eigen::Vector2d& px) const;
  // Every junction inside the circle, refined and merged.
  std::vector<Junction> FindInCircle(const Eigen::Vector2d& centre, double radius) const;

  const cv::Mat& ridge() const { return ridge_; }  // CV_32F, the ROI
  double peak_threshold() const { return threshold_; }

 private:
  // Ridge strength on a circle (bilinear), n samples from angle 0.
  std::vector<double> Ring(const Eigen::Vector2d& centre, double radius, int n) const;
  // Peak angles (rad, sub-sample) of a circular profile above the threshold.
  std::vector<double> Peaks(const std::vector<double>& profile, double* weakest) const;
  double Sample(double x, double y) const;  // R at image coordinates (bilinear), 0 outside

  KnotDetectorOptions o_;
  cv::Rect roi_;
  cv::Mat ridge_;
  double threshold_ = 0.0;
};

enum class FindNodeStatus { kFound, kNone, kSeveral };

struct FindNodeResult {
  FindNodeStatus status = FindNodeStatus::kNone;
  Junction knot;                     // when found
  std::vector<Junction> candidates;  // when several (and the one found)
  std::string why;                   // when not found
};

// The knot inside the brush (centre, radius in px) of `image`.
FindNodeResult FindNode(const cv::Mat& image, const Eigen::Vector2d& centre, double radius,
                        const KnotDetectorOptions& options = {});

// Find Path: the knots strictly between two labeled knots of one row or column, found by
// following the yarn (the cheapest path on 1 / ridge strength from one knot to the other) and
// taking the junctions on it in order. Refused (ok false, with the reason) when the knots are not
// in one row or column, when the number of junctions found differs from the knots between, or
// when they are unevenly spaced along the yarn (a gap under half or over 1.6 times the mean: a
// knot missed and a false junction taken instead).
struct FindPathResult {
  bool ok = false;
  std::string why;
  std::vector<int> knots;           // row * cols + col of each knot between, from a towards b
  std::vector<Junction> junctions;  // their junctions, in the same order
  std::vector<Eigen::Vector2d> path;  // the followed yarn, pixel by pixel
};

FindPathResult FindPath(const cv::Mat& image, int cols, int knot_a, const Eigen::Vector2d& px_a,
                        int knot_b, const Eigen::Vector2d& px_b,
                        const KnotDetectorOptions& options = {});

}  // namespace netlab::recon
