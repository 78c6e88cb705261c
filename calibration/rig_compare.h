#pragma once
// How far a calibrated rig is from the true one (synthetic experiments, `netlab calibrate
// --truth`).
//
// Calibration fixes its own gauge (the world is the target in the reference camera's first
// frame), so the estimated world frame differs from the true one by a rigid transform. CompareRigs
// first finds that transform, true_world_from_estimated_world (rotation R, translation t, no scale:
// the calibration is metric and a scale error is to be reported, not absorbed), then measures each
// camera in the aligned frame:
//   aligned cam_from_world = estimated cam_from_world * true_world_from_estimated_world^-1,
//   so an aligned centre is R c_est + t and an aligned orientation R_est R^T.
//
// Alignment (RigAlignment):
//   kCentres: with >= 3 cameras whose true centres are not (nearly) collinear, the least-squares
//     rigid fit of the estimated centres onto the true ones (Umeyama 1991, "Least-squares
//     estimation of transformation parameters between two point patterns"; Eigen::umeyama without
//     scaling). "Not collinear": the second singular value of the centred 3 x n matrix of true
//     centres is at least kMinCentreSpread times the first. Below that the rotation about the
//     centres' main axis hangs on a lever arm under a tenth of the rig's extent, and a millimetre
//     of centre error would tilt every camera by more than a calibration's own orientation error.
//   kMeanRotationAndCentroid: otherwise (one or two cameras, or collinear centres) the centres do
//     not fix the rotation, so the orientations do: R is the chordal L2 mean of the rotations each
//     camera implies, R_true_i^T R_est_i (their sum projected onto SO(3) by SVD; Hartley et al.
//     2013, "Rotation averaging", IJCV), and t maps the estimated centroid onto the true one.
//     With two cameras a relative rotation error then splits evenly between them.
//
// Intrinsics: fx, fy, cx, cy errors are estimated - true (px). The "image error" compares whole
// projections, distortion included: the pixels of a kImageGrid x kImageGrid grid spanning the
// image (first to last pixel centre, both ends included) are turned into camera rays with the
// true intrinsics (UndistortPoint), the rays projected with both the estimated and the true
// intrinsics, and the RMS and the largest distance between the two pixels reported. Grid pixels
// whose true distortion does not invert are skipped.

#include <string>
#include <vector>

#include "calibration/rig.h"
#include "calibration/rigid3.h"

namespace netlab::calib {

// kNone: the two rigs share their world frame (a marker-map calibration is expressed in the map's
// frame, which is the true world): compared as they are.
enum class RigAlignment { kCentres, kMeanRotationAndCentroid, kNone };

struct CameraComparison {
  std::string name;
  double centre_error_m = 0.0;      // |aligned centre - true centre|, m
  double rotation_error_deg = 0.0;  // angle of R_true^T R_aligned, deg
  double fx_error_px = 0.0;         // estimated - true, px
  double fy_error_px = 0.0;
  double cx_error_px = 0.0;
  double cy_error_px = 0.0;
  double image_error_rms_px = 0.0;  // over the grid of rays (header comment), px
  double image_error_max_px = 0.0;
};

struct RigComparison {
  std::vector<CameraComparison> cameras;  // in the estimated rig's order
  RigAlignment alignment = RigAlignment::kCentres;
  // x_in_true_world = true_world_from_estimated_world * x_in_estimated_world.
  Rigid3d true_world_from_estimated_world;
  double alignment_rms_m = 0.0;    // RMS of centre_error_m: the alignment's residual, m
  double alignment_rms_deg = 0.0;  // RMS of rotation_error_deg, deg
  // Sum of the pairwise centre distances, estimated over true, minus 1 (0.001: the estimated rig
  // is 0.1 % too large). NaN with a single camera.
  double scale_error = 0.0;

  double max_centre_error_m() const;
  double max_rotation_error_deg() const;
  // A few lines: the alignment, then one table row per camera (mm, deg, px).
  std::string Report() const;
};

// Points per side of the image grid of the intrinsics comparison.
inline constexpr int kImageGrid = 21;
// Second over first singular value of the centred true centres below which they count as
// collinear (header comment).
inline constexpr double kMinCentreSpread = 0.1;

// Compares `estimated` with `truth`, cameras matched by name. Throws std::runtime_error naming the
// camera when one is in only one of the rigs, or when a camera's image size differs between them;
// and when `estimated` has no cameras.
RigComparison CompareRigs(const Rig& estimated, const Rig& truth, bool same_world_frame = false);

}  // namespace netlab::calib
