#include "calibration/rig_compare.h"

#include <Eigen/Geometry>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "calibration/camera.h"

namespace netlab::calib {
namespace {

constexpr double kRadToDeg = 180.0 / M_PI;

// The rotation nearest (Frobenius) to `m`: U diag(1, 1, det(U V^T)) V^T of its SVD.
Eigen::Matrix3d NearestRotation(const Eigen::Matrix3d& m) {
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(m, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d d = Eigen::Matrix3d::Identity();
  d(2, 2) = (svd.matrixU() * svd.matrixV().transpose()).determinant() < 0.0 ? -1.0 : 1.0;
  return svd.matrixU() * d * svd.matrixV().transpose();
}

struct ImageError {
  double rms_px, max_px;
};

// Pixel distances between the estimated and the true intrinsics over the same rays (header).
ImageError CompareImages(const CameraIntrinsics& estimated, const CameraIntrinsics& truth) {
  double sum_sq = 0.0, max = 0.0;
  int n = 0;
  for (int i = 0; i < kImageGrid; ++i) {
    for (int j = 0; j < kImageGrid; ++j) {
      const Eigen::Vector2d pixel((truth.width - 1) * double(j) / (kImageGrid - 1),
                                  (truth.height - 1) * double(i) / (kImageGrid - 1));
      const Eigen::Vector2d xy = UndistortPoint(truth, pixel);
      if (!xy.allFinite()) continue;  // the true distortion does not invert here
      const Eigen::Vector3d ray(xy.x(), xy.y(), 1.0);
      const double d = (Project(estimated, ray) - Project(truth, ray)).norm();
      sum_sq += d * d;
      max = std::max(max, d);
      ++n;
    }
  }
  const double nan = std::numeric_limits<double>::quiet_NaN();
  if (n == 0) return {nan, nan};
  return {std::sqrt(sum_sq / n), max};
}

// Sum of the distances between every pair of centres, m.
double SumOfBaselines(const std::vector<Eigen::Vector3d>& centres) {
  double sum = 0.0;
  for (size_t a = 0; a < centres.size(); ++a)
    for (size_t b = a + 1; b < centres.size(); ++b) sum += (centres[a] - centres[b]).norm();
  return sum;
}

std::string Fixed(const char* format, double value) {
  char buffer[32];
  std::snprintf(buffer, sizeof(buffer), format, value);
  return buffer;
}

}  // namespace

double RigComparison::max_centre_error_m() const {
  double m = 0.0;
  for (const CameraComparison& c : cameras) m = std::max(m, c.centre_error_m);
  return m;
}

double RigComparison::max_rotation_error_deg() const {
  double m = 0.0;
  for (const CameraComparison& c : cameras) m = std::max(m, c.rotation_error_deg);
  return m;
}

std::string RigComparison::Report() const {
  std::ostringstream os;
  os << "rig vs truth: "
     << (alignment == RigAlignment::kNone      ? "one world frame, not aligned"
         : alignment == RigAlignment::kCentres ? "aligned on the camera centres"
                                               : "aligned on the mean orientation and the centroid")
     << " (residual " << Fixed("%.3f", alignment_rms_m * 1e3) << " mm, "
     << Fixed("%.4f", alignment_rms_deg) << " deg RMS); scale error "
     << (std::isfinite(scale_error) ? Fixed("%+.4f", scale_error * 100.0) + " %" : "n/a") << "\n";
  char line[200];
  std::snprintf(line, sizeof(line), "  %-10s %9s %9s %8s %8s %8s %8s %9s %9s\n", "camera",
                "centre mm", "rot deg", "fx px", "fy px", "cx px", "cy px", "img RMS", "img max");
  os << line;
  for (const CameraComparison& c : cameras) {
    std::snprintf(line, sizeof(line),
                  "  %-10s %9.3f %9.4f %+8.3f %+8.3f %+8.3f %+8.3f %9.3f %9.3f\n", c.name.c_str(),
                  c.centre_error_m * 1e3, c.rotation_error_deg, c.fx_error_px, c.fy_error_px,
                  c.cx_error_px, c.cy_error_px, c.image_error_rms_px, c.image_error_max_px);
    os << line;
  }
  return os.str();
}

RigComparison CompareRigs(const Rig& estimated, const Rig& truth, bool same_world_frame) {
  // Match the cameras by name, both ways.
  if (estimated.cameras.empty()) throw std::runtime_error("rig comparison: no cameras");
  for (const Camera& c : truth.cameras)
    if (estimated.Find(c.name) < 0)
      throw std::runtime_error("rig comparison: camera '" + c.name +
                               "' of the true rig is not in the estimated rig");
  std::vector<const Camera*> true_of;  // per estimated camera
  for (const Camera& c : estimated.cameras) {
    const int i = truth.Find(c.name);
    if (i < 0)
      throw std::runtime_error("rig comparison: camera '" + c.name +
                               "' of the estimated rig is not in the true rig");
    const CameraIntrinsics& k = truth.cameras[i].intrinsics;
    if (k.width != c.intrinsics.width || k.height != c.intrinsics.height)
      throw std::runtime_error(
          "rig comparison: camera '" + c.name + "' has " + std::to_string(c.intrinsics.width) +
          "x" + std::to_string(c.intrinsics.height) + " pixels in the estimated rig but " +
          std::to_string(k.width) + "x" + std::to_string(k.height) + " in the true rig");
    true_of.push_back(&truth.cameras[i]);
  }
  const int n = static_cast<int>(estimated.cameras.size());

  // Centres as 3 x n matrices, and the spread of the true ones.
  Eigen::Matrix3Xd est_centres(3, n), true_centres(3, n);
  for (int i = 0; i < n; ++i) {
    est_centres.col(i) = estimated.cameras[i].Center();
    true_centres.col(i) = true_of[i]->Center();
  }
  const Eigen::Vector3d est_centroid = est_centres.rowwise().mean();
  const Eigen::Vector3d true_centroid = true_centres.rowwise().mean();
  const Eigen::Matrix3Xd spread = true_centres.colwise() - true_centroid;
  const Eigen::Vector3d singular = Eigen::JacobiSVD<Eigen::Matrix3Xd>(spread).singularValues();
  const bool centres_fix_rotation = n >= 3 && singular(1) >= kMinCentreSpread * singular(0);

  // true_world_from_estimated_world (header comment).
  RigComparison result;
  if (same_world_frame) {
    result.alignment = RigAlignment::kNone;  // identity
  } else if (centres_fix_rotation) {
    result.alignment = RigAlignment::kCentres;
    const Eigen::Matrix4d t = Eigen::umeyama(est_centres, true_centres, /*with_scaling=*/false);
    result.true_world_from_estimated_world = Rigid3d(Eigen::Matrix3d(t.topLeftCorner<3, 3>()),
                                                     Eigen::Vector3d(t.topRightCorner<3, 1>()));
  } else {
    result.alignment = RigAlignment::kMeanRotationAndCentroid;
    // Camera i alone implies R = R_true_i^T R_est_i (it makes R_est_i R^T = R_true_i).
    Eigen::Matrix3d sum = Eigen::Matrix3d::Zero();
    for (int i = 0; i < n; ++i)
      sum += true_of[i]->cam_from_world.RotationMatrix().transpose() *
             estimated.cameras[i].cam_from_world.RotationMatrix();
    const Eigen::Matrix3d r = NearestRotation(sum);
    result.true_world_from_estimated_world = Rigid3d(r, true_centroid - r * est_centroid);
  }
  const Rigid3d estimated_world_from_true_world = result.true_world_from_estimated_world.Inverse();

  // Per camera: pose in the aligned frame, intrinsics, image error.
  double sum_sq_m = 0.0, sum_sq_deg = 0.0;
  for (int i = 0; i < n; ++i) {
    const Camera& est = estimated.cameras[i];
    const Camera& tru = *true_of[i];
    const Rigid3d aligned = est.cam_from_world * estimated_world_from_true_world;
    CameraComparison c;
    c.name = est.name;
    c.centre_error_m = (aligned.Inverse().translation - tru.Center()).norm();
    c.rotation_error_deg = Rigid3d::AngleBetween(aligned, tru.cam_from_world) * kRadToDeg;
    c.fx_error_px = est.intrinsics.fx - tru.intrinsics.fx;
    c.fy_error_px = est.intrinsics.fy - tru.intrinsics.fy;
    c.cx_error_px = est.intrinsics.cx - tru.intrinsics.cx;
    c.cy_error_px = est.intrinsics.cy - tru.intrinsics.cy;
    const ImageError image = CompareImages(est.intrinsics, tru.intrinsics);
    c.image_error_rms_px = image.rms_px;
    c.image_error_max_px = image.max_px;
    sum_sq_m += c.centre_error_m * c.centre_error_m;
    sum_sq_deg += c.rotation_error_deg * c.rotation_error_deg;
    result.cameras.push_back(c);
  }
  result.alignment_rms_m = std::sqrt(sum_sq_m / n);
  result.alignment_rms_deg = std::sqrt(sum_sq_deg / n);

  // Scale: invariant under the alignment, so from the centres as given.
  std::vector<Eigen::Vector3d> est_list, true_list;
  for (int i = 0; i < n; ++i) {
    est_list.push_back(est_centres.col(i));
    true_list.push_back(true_centres.col(i));
  }
  const double true_sum = SumOfBaselines(true_list);
  result.scale_error = true_sum > 0.0 ? SumOfBaselines(est_list) / true_sum - 1.0
                                      : std::numeric_limits<double>::quiet_NaN();
  return result;
}

}  // namespace netlab::calib
