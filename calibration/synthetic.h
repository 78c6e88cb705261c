#pragma once
// The synthetic generator: what a camera of the rig sees of printed planes (calibration boards,
// foils, marker maps), rendered through the exact camera model, with ground truth. Every
// estimator of calibration/ (and later of libreconstruct/) is tested against it.
//
// Rendering: for each pixel corner the undistorted ray is computed once per camera (CameraRays);
// each print maps rays to its plane by a homography; a pixel whose four corners see the same
// colour takes it, an edge pixel averages supersample x supersample samples (area sampling), so
// printed edges land with sub-pixel accuracy. The nearest print in front of the camera wins
// (occlusion); a print seen from behind is not drawn (the foil's other side is its own print).

#include <cstdint>
#include <memory>
#include <opencv2/core.hpp>
#include <random>
#include <vector>

#include "calibration/rig.h"
#include "calibration/target.h"

namespace netlab::calib {

// Something printed on a plane, in its own frame (x, y on the plane, m).
class PlanarPrint {
 public:
  virtual ~PlanarPrint() = default;
  // Reflectance in [0, 1] at (x, y), or a negative value outside the print.
  virtual double Albedo(double x, double y) const = 0;
  // Outline of the print (for culling), m.
  virtual Eigen::Vector2d Min() const = 0;
  virtual Eigen::Vector2d Max() const = 0;
  // Side of the plane (sign of z) from which the print is seen.
  virtual double ViewerZ() const { return -1.0; }
};

// The prints of a target with their poses: a board gives one, a foil two (front and back), a
// marker map one per marker.
struct TargetPrint {
  std::shared_ptr<const PlanarPrint> print;
  Rigid3d target_from_print;
};
std::vector<TargetPrint> MakeTargetPrints(const CalibrationTarget& target);

// Undistorted rays (normalised coordinates x/z, y/z) through every pixel corner of a camera.
class CameraRays {
 public:
  explicit CameraRays(const CameraIntrinsics& intrinsics);
  const CameraIntrinsics& intrinsics() const { return intrinsics_; }
  // Ray through the corner at (u - 1/2, v - 1/2), u in [0, width], v in [0, height].
  Eigen::Vector2d Corner(int u, int v) const {
    const cv::Vec2f& r = corners_.at<cv::Vec2f>(v, u);
    return {r[0], r[1]};
  }

 private:
  CameraIntrinsics intrinsics_;
  cv::Mat corners_;  // (height + 1) x (width + 1), CV_32FC2
};

struct RenderOptions {
  double black = 25.0;       // grey level of black print
  double white = 225.0;      // grey level of white print
  double background = 90.0;  // grey level where no print is seen
  double noise_sigma = 0.0;  // Gaussian sensor noise, grey levels
  uint64_t seed = 1;
  int supersample = 4;  // samples per pixel side at edges
};

struct PrintPose {
  const PlanarPrint* print;
  Rigid3d cam_from_print;
};

// An 8-bit grey image of `prints` as seen by the camera of `rays`.
cv::Mat RenderPrints(const CameraRays& rays, const std::vector<PrintPose>& prints,
                     const RenderOptions& options);

// The same for a whole target at world_from_target seen by `camera`.
cv::Mat RenderTarget(const Camera& camera, const CameraRays& rays,
                     const std::vector<TargetPrint>& prints, const Rigid3d& world_from_target,
                     const RenderOptions& options);

// True projections of a target's points: per face, the ids and pixels of the points in front of
// the camera, on the seen side of their face and at least `margin_px` inside the image.
struct FaceProjection {
  int face = 0;
  std::vector<int> ids;
  std::vector<Eigen::Vector2d> pixels;
};
std::vector<FaceProjection> ProjectTarget(const Camera& camera, const CalibrationTarget& target,
                                          const Rigid3d& world_from_target, double margin_px = 0.0);

// A world_from_face orientation facing cameras that look along +x (the paper rig's cam0/cam1):
// face x to their right (-y), face y down (-z), the print seen from -x.
Eigen::Quaterniond FacingPlusX(const BoardPattern& pattern);

// Random poses of `target` that every camera in `must_see` sees entirely (every point of some
// face, at least `margin_px` inside the image, from the printed side). The target is placed
// around `center` (world) within `spread` (m) per axis, turned by up to `max_tilt_rad` from
// `base` (world_from_target orientation). Throws std::runtime_error if no pose is found after
// many tries.
std::vector<Rigid3d> RandomTargetPoses(const Rig& rig, const CalibrationTarget& target,
                                       const std::vector<int>& must_see, int count,
                                       const Eigen::Vector3d& center, const Eigen::Vector3d& spread,
                                       const Eigen::Quaterniond& base, double max_tilt_rad,
                                       std::mt19937& rng, double margin_px = 10.0);

}  // namespace netlab::calib
