#pragma once
// Triangulation of one point from two or more calibrated views, with outlier rejection and
// uncertainty.
//
//   1. Linear: DLT on undistorted normalised coordinates (the full lens model inverted first),
//      each equation scaled to unit norm, solved by SVD.
//   2. Nonlinear: Gauss-Newton with Levenberg damping on the pixel reprojection error through the
//      full camera model (calibration/camera.h), observations weighted by Huber's function.
//   3. Outliers: with three or more views, when an observation's residual exceeds the threshold,
//      every pair of views is triangulated and refined; the largest set of views that a pair's
//      point explains within the threshold wins, and the observations it leaves out are outliers:
//      reported and left out. When two different sets tie for largest (a mislabel on the
//      epipolar line of a good view agrees with it), or two views disagree, nothing says which
//      view is wrong: the point is left untriangulated and the suspects are reported.
//
// Covariance: sigma^2 (J^T J)^-1 with J the Jacobian of the inlier residuals in px at the
// solution: first order, exact for Gaussian pixel noise of standard deviation sigma in the limit
// of small noise, and what the Cramer-Rao bound is at the true point.

#include <Eigen/Core>
#include <optional>
#include <string>
#include <vector>

#include "calibration/rig.h"

namespace netlab::recon {

struct Observation {
  int camera = 0;      // index into the rig
  Eigen::Vector2d px;  // OpenCV pixel convention
};

struct TriangulationOptions {
  // An observation whose reprojection residual exceeds this is an outlier (px). Keep it above
  // ~4 sigma of the labelling noise.
  double outlier_threshold_px = 4.0;
  // Huber's threshold of the refinement (px): quadratic below, linear above.
  double huber_px = 2.0;
  int max_iterations = 20;
};

struct PointEstimate {
  bool valid = false;
  std::string why;                                     // when not valid
  Eigen::Vector3d position = Eigen::Vector3d::Zero();  // world, m
  // (J^T J)^-1 of the inlier residuals in px: the covariance for sigma = 1 px (m^2 / px^2).
  Eigen::Matrix3d unit_covariance = Eigen::Matrix3d::Zero();
  double rms_px = 0.0;              // RMS inlier residual (over the 2n residual components / 2)
  double sum_squares_px2 = 0.0;     // sum of squared inlier residual components
  std::vector<int> inliers;         // indices into the observations
  std::vector<int> outliers;        // indices into the observations
  std::vector<double> residual_px;  // per observation (all of them), px; NaN behind a camera
};

// Linear triangulation. False when fewer than two observations can be undistorted or the
// solution is at infinity.
bool TriangulateLinear(const calib::Rig& rig, const std::vector<Observation>& observations,
                       Eigen::Vector3d* position);

// Nonlinear refinement of `position` from the given observations (all used, Huber-weighted).
// False when it leaves the front of a camera or diverges.
bool RefinePoint(const calib::Rig& rig, const std::vector<Observation>& observations,
                 const TriangulationOptions& options, Eigen::Vector3d* position);

// The whole: linear start, refinement, outliers, covariance.
PointEstimate TriangulatePoint(const calib::Rig& rig, const std::vector<Observation>& observations,
                               const TriangulationOptions& options = {});

// sum_i J_i^T J_i at a world point for the given cameras (J_i: d pixel / d point, px / m): the
// Fisher information for sigma = 1 px. Its inverse times sigma^2 is the Cramer-Rao bound of any
// unbiased estimate of the point from those views.
Eigen::Matrix3d PointInformation(const calib::Rig& rig, const std::vector<int>& cameras,
                                 const Eigen::Vector3d& position);

// A point's largest standard deviation (m) for `label_sigma_px` px of label noise per axis in
// each view: the square root of the largest eigenvalue of its covariance, as `netlab triangulate
// --max-sigma-mm` bounds it (bundle_adjust.h); infinite when the estimate is not valid.
double LargestSigmaM(const PointEstimate& estimate, double label_sigma_px = 1.0);

// A usable ray geometry: the point's largest standard deviation at most `max_unit_sigma_m` for
// 1 px of label noise. Views whose rays meet nearly parallel or head-on fail it: two cameras
// facing each other, the knot near the line between them (rays 0.00 deg from head-on), fit
// any point along that line, and the one their solver returns is meaningless (on the demo shot
// 2.8-3.1 m at 0.1 px, projected 1260-1556 px from a correct label). The default,
// kMaxUnitSigmaM, is 50 mm per px: 5 mm at the labels' 0.1 px; the demo rig's points have
// 1-3 mm per px.
constexpr double kMaxUnitSigmaM = 0.05;
bool UsableGeometry(const PointEstimate& estimate, double max_unit_sigma_m = kMaxUnitSigmaM);

// Where views that agree with each other put a point in another camera: their point (no
// outlier among them) projected into rig camera `camera`, and that projection's covariance for
// 1 px of noise per axis in each view (J C J^T, C the point's unit covariance, J the
// projection's Jacobian). Nullopt where they do not triangulate without an outlier, their ray
// geometry is not usable (UsableGeometry: the first-order covariance does not say how far off
// such a point is) or the point is behind that camera.
struct ProjectedPoint {
  Eigen::Vector2d px = Eigen::Vector2d::Zero();
  Eigen::Matrix2d unit_covariance = Eigen::Matrix2d::Zero();  // px^2 per px^2 of label noise
};
std::optional<ProjectedPoint> ProjectAgreeingViews(const calib::Rig& rig, int camera,
                                                   const std::vector<Observation>& views,
                                                   const TriangulationOptions& options = {});

// A point's projection into rig camera `camera`, with that projection's covariance for 1 px of
// noise per axis in each view (J C J^T, C the estimate's unit covariance); nullopt where the
// estimate is not valid or the point is behind that camera.
std::optional<ProjectedPoint> ProjectEstimate(const calib::Rig& rig, int camera,
                                              const PointEstimate& estimate);

// The pixel of a world point in `camera` and, when asked, its Jacobian (px / m); false behind
// the camera.
bool PixelAndJacobian(const calib::Camera& camera, const Eigen::Vector3d& p_in_world,
                      Eigen::Vector2d* pixel, Eigen::Matrix<double, 2, 3>* wrt_world);

// Residual (px) of one observation at `position` (NaN behind the camera).
double ReprojectionResidual(const calib::Rig& rig, const Observation& observation,
                            const Eigen::Vector3d& position);

}  // namespace netlab::recon
