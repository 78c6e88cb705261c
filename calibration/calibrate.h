#pragma once
// Rig calibration: detections of a target in synchronized frames of several cameras -> every
// camera's intrinsics and cam_from_world in one world frame.
//
// Pipeline (CalibrateRig):
//   1. per-camera intrinsics from its planar views (OpenCV's Zhang method), unless given;
//   2. per-view target poses by PnP;
//   3. for a double-sided foil, which side each camera sees: the one that makes its pose
//      relative to the other cameras consistent over the frames they share (or as the foil file
//      says);
//   4. a pose graph over cameras and frames initialises every camera and target pose;
//   5. one Ceres bundle adjustment over all camera poses, target poses and (optionally)
//      intrinsics, with a Huber loss; observations beyond the outlier threshold are dropped and
//      the problem solved again;
//   6. a report: RMS per camera and image, image coverage, baselines, and a metric check
//      (adjacent corners triangulated by each camera pair and measured against the square size).
//
// World frame: the target's frame in the first frame the reference camera (the one with the
// most views) sees it; for a marker map, the map's frame.

#include <functional>
#include <map>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "calibration/detect.h"
#include "calibration/rig.h"
#include "calibration/target.h"
#include "common/progress.h"

namespace netlab::calib {

// The points of one face seen by one camera in one frame.
struct Observation {
  int camera = 0;
  int frame = 0;
  int face = 0;  // set by the pipeline for a foil
  std::vector<int> ids;
  std::vector<Eigen::Vector2d> pixels;
};

// The observation of `found` by `camera` in `frame` (face 0 until the pipeline assigns one).
inline Observation MakeObservation(int camera, int frame, const PatternDetection& found) {
  Observation o;
  o.camera = camera;
  o.frame = frame;
  o.ids = found.ids;
  o.pixels = found.pixels;
  return o;
}

struct CalibrationInput {
  std::vector<std::string> camera_names;
  std::vector<cv::Size> image_sizes;                  // per camera
  std::vector<std::vector<std::string>> image_names;  // [camera][frame], for reports (optional)
  int num_frames = 0;
  std::vector<Observation> observations;
};

struct CalibrationOptions {
  bool rational = false;          // estimate k4..k6 as well (rational model)
  bool refine_intrinsics = true;  // let the bundle adjustment refine the intrinsics
  // Known intrinsics by camera name (--fix-intrinsics): held constant.
  std::map<std::string, CameraIntrinsics> fixed_intrinsics;
  double huber_px = 1.0;    // scale of the Huber loss, px
  double outlier_px = 1.0;  // observations beyond max(outlier_px, 5 robust sigma) are dropped
  int min_views = 5;        // a camera with fewer views gets a warning
  double min_view_spread_deg = 15.0;  // all of a camera's views within this angle: warning
  double min_coverage = 0.3;          // fraction of the image's 10 x 10 cells with points: warning
  int max_iterations = 200;

  bool IsValid(std::string* error) const;
};

struct CameraReport {
  std::string name;
  double rms_px = 0.0;
  int views = 0;
  int points = 0;
  double coverage = 0.0;  // fraction of 10 x 10 image cells holding an inlier
  std::vector<std::pair<int, double>> image_rms_px;  // (frame, rms)
  double position_sigma_m = 0.0;  // 1-sigma of the camera centre from the solver's covariance
};

struct PairCheck {
  std::string a, b;
  double baseline_m = 0.0;
  int segments = 0;             // adjacent point pairs triangulated by both
  double mean_length_mm = 0.0;  // recovered square (or marker side), mm
  double nominal_length_mm = 0.0;
  double rms_error_mm = 0.0;  // against the nominal length
};

struct CalibrationSummary {
  double rms_px = 0.0;
  int observations = 0;  // points used
  int outliers = 0;      // points dropped
  std::vector<CameraReport> cameras;
  std::vector<PairCheck> pairs;
  std::vector<std::string> warnings;
  std::vector<int> face_of_camera;  // the face each camera saw (foil: 0 front, 1 back)
  double wall_s = 0.0;
  std::string BriefReport() const;
};

struct CalibrationResult {
  Rig rig;
  CalibrationSummary summary;
  std::vector<Rigid3d> world_from_target;  // per frame (identity where not seen)
  std::vector<bool> frame_seen;
};

// Throws std::runtime_error naming the camera (and images) when a camera has no views, too few to
// estimate its intrinsics, or shares no frame with the others.
CalibrationResult CalibrateRig(const CalibrationTarget& target, const CalibrationInput& input,
                               const CalibrationOptions& options);

// The files a glob pattern names (~ and {a,b} expanded), sorted: the order DetectInImages
// takes them in. Empty when none match.
std::vector<std::string> ImagesMatching(const std::string& pattern);

// Image files per camera (sorted: the index is the frame) -> detections. Throws
// std::runtime_error naming the file on an unreadable image or one whose size differs from its
// camera's first; and naming the camera and images when the target is found in none of them.
// Progress: stage "images searched" (of all cameras), from any of the threads (one at a
// time); a cancel stops them between images and throws Cancelled. Detection runs on `threads`
// threads.
CalibrationInput DetectInImages(const std::vector<std::string>& camera_names,
                                const std::vector<std::vector<std::string>>& files,
                                const CalibrationTarget& target,
                                const ProgressReporter& progress = {}, int threads = 2);

}  // namespace netlab::calib
