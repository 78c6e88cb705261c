#include "calibration/camera.h"

#include <ceres/jet.h>

#include <Eigen/Dense>
#include <cmath>
#include <limits>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>

namespace netlab::calib {

Eigen::Matrix3d CameraIntrinsics::K() const {
  Eigen::Matrix3d k;
  k << fx, 0, cx, 0, fy, cy, 0, 0, 1;
  return k;
}

cv::Mat CameraIntrinsics::CameraMatrix() const {
  return (cv::Mat_<double>(3, 3) << fx, 0, cx, 0, fy, cy, 0, 0, 1);
}

cv::Mat CameraIntrinsics::DistortionCoefficients() const {
  cv::Mat d(1, num_distortion(), CV_64F);
  for (int i = 0; i < num_distortion(); ++i) d.at<double>(0, i) = distortion[i];
  return d;
}

std::array<double, kNumIntrinsics> CameraIntrinsics::ToParameters() const {
  std::array<double, kNumIntrinsics> p{};
  p[0] = fx;
  p[1] = fy;
  p[2] = cx;
  p[3] = cy;
  for (int i = 0; i < 8; ++i) p[4 + i] = distortion[i];
  return p;
}

void CameraIntrinsics::FromParameters(const double* p) {
  fx = p[0];
  fy = p[1];
  cx = p[2];
  cy = p[3];
  for (int i = 0; i < 8; ++i) distortion[i] = p[4 + i];
}

bool CameraIntrinsics::IsValid(std::string* error) const {
  std::ostringstream os;
  if (width <= 0 || height <= 0) {
    os << "image size " << width << "x" << height << " must be positive";
  } else if (!(fx > 0.0) || !(fy > 0.0) || !std::isfinite(fx) || !std::isfinite(fy)) {
    os << "focal lengths must be positive (fx " << fx << ", fy " << fy << ")";
  } else if (!std::isfinite(cx) || !std::isfinite(cy)) {
    os << "principal point must be finite";
  } else {
    for (double d : distortion)
      if (!std::isfinite(d)) os << "distortion coefficients must be finite";
  }
  if (os.str().empty()) return true;
  if (error) *error = os.str();
  return false;
}

Eigen::Vector2d Project(const CameraIntrinsics& camera, const Eigen::Vector3d& p_in_cam) {
  const auto k = camera.ToParameters();
  Eigen::Vector2d pixel;
  if (!ProjectPoint(k.data(), p_in_cam.data(), pixel.data()))
    pixel.setConstant(std::numeric_limits<double>::quiet_NaN());
  return pixel;
}

ProjectionJacobian ProjectWithJacobian(const CameraIntrinsics& camera,
                                       const Eigen::Vector3d& p_in_cam) {
  // Forward-mode automatic differentiation over the 3 point and 12 intrinsic parameters.
  using Jet = ceres::Jet<double, 3 + kNumIntrinsics>;
  const auto k = camera.ToParameters();
  Jet point[3], intrinsics[kNumIntrinsics], pixel[2];
  for (int i = 0; i < 3; ++i) point[i] = Jet(p_in_cam[i], i);
  for (int i = 0; i < kNumIntrinsics; ++i) intrinsics[i] = Jet(k[i], 3 + i);
  ProjectionJacobian out;
  if (!ProjectPoint(intrinsics, point, pixel)) {
    out.pixel.setConstant(std::numeric_limits<double>::quiet_NaN());
    out.wrt_point.setConstant(std::numeric_limits<double>::quiet_NaN());
    out.wrt_intrinsics.setConstant(std::numeric_limits<double>::quiet_NaN());
    return out;
  }
  for (int r = 0; r < 2; ++r) {
    out.pixel[r] = pixel[r].a;
    out.wrt_point.row(r) = pixel[r].v.head<3>().transpose();
    out.wrt_intrinsics.row(r) = pixel[r].v.tail<kNumIntrinsics>().transpose();
  }
  return out;
}

Eigen::Vector2d UndistortPoint(const CameraIntrinsics& camera, const Eigen::Vector2d& pixel) {
  // Solve Distort(x, y) = (xd, yd) by Newton's method from the distorted point itself.
  const double xd = (pixel.x() - camera.cx) / camera.fx;
  const double yd = (pixel.y() - camera.cy) / camera.fy;
  using Jet = ceres::Jet<double, 2>;
  Jet d[8];
  for (int i = 0; i < 8; ++i) d[i] = Jet(camera.distortion[i]);
  double x = xd, y = yd;
  for (int iteration = 0; iteration < 50; ++iteration) {
    Jet fx_jet, fy_jet;
    Distort(d, Jet(x, 0), Jet(y, 1), &fx_jet, &fy_jet);
    const double rx = fx_jet.a - xd, ry = fy_jet.a - yd;
    if (rx * rx + ry * ry < 1e-28) return {x, y};
    Eigen::Matrix2d j;
    j << fx_jet.v[0], fx_jet.v[1], fy_jet.v[0], fy_jet.v[1];
    const double det = j.determinant();
    if (!(std::abs(det) > 1e-12)) break;
    const Eigen::Vector2d step = j.inverse() * Eigen::Vector2d(rx, ry);
    x -= step.x();
    y -= step.y();
    if (!std::isfinite(x) || !std::isfinite(y)) break;
  }
  // Accept a converged-enough answer, else say so.
  Jet fx_jet, fy_jet;
  Distort(d, Jet(x), Jet(y), &fx_jet, &fy_jet);
  const double residual = std::hypot(fx_jet.a - xd, fy_jet.a - yd) * camera.fx;
  if (residual < 1e-6) return {x, y};
  return Eigen::Vector2d::Constant(std::numeric_limits<double>::quiet_NaN());
}

cv::Mat UndistortImage(const CameraIntrinsics& camera, const cv::Mat& image) {
  cv::Mat out;
  cv::undistort(image, out, camera.CameraMatrix(), camera.DistortionCoefficients());
  return out;
}

}  // namespace netlab::calib
