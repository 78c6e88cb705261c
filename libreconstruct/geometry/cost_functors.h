#pragma once
// The Ceres residuals of the sequence reconstruction (bundle_adjust.h): reprojection in a fixed
// or a moving camera (px), and the two priors on the points (dimensionless, in sigmas).
// Points are world positions in m, 3 doubles each. Each functor's Create() returns a new
// AutoDiffCostFunction that the ceres::Problem it is added to takes ownership of.

#include <ceres/ceres.h>
#include <ceres/rotation.h>

#include <Eigen/Core>
#include <array>

#include "calibration/rig.h"

namespace netlab::recon {

// Reprojection residual of a world point p in a camera held fixed (px): project(p) - px.
struct FixedCameraReprojection {
  FixedCameraReprojection(const calib::Camera& camera, const Eigen::Vector2d& px) : px_(px) {
    k_ = camera.intrinsics.ToParameters();
    const Eigen::Matrix3d r = camera.cam_from_world.RotationMatrix();
    for (int i = 0; i < 9; ++i) r_[i] = r(i / 3, i % 3);
    for (int i = 0; i < 3; ++i) t_[i] = camera.cam_from_world.translation[i];
  }
  template <typename T>
  bool operator()(const T* p, T* residual) const {
    T pc[3], k[calib::kNumIntrinsics], pixel[2];
    for (int i = 0; i < 3; ++i)
      pc[i] = T(r_[3 * i]) * p[0] + T(r_[3 * i + 1]) * p[1] + T(r_[3 * i + 2]) * p[2] + T(t_[i]);
    for (int i = 0; i < calib::kNumIntrinsics; ++i) k[i] = T(k_[i]);
    if (!calib::ProjectPoint(k, pc, pixel)) return false;
    residual[0] = pixel[0] - T(px_.x());
    residual[1] = pixel[1] - T(px_.y());
    return true;
  }
  // Residual block of size 2 on the point (3).
  static ceres::CostFunction* Create(const calib::Camera& camera, const Eigen::Vector2d& px) {
    return new ceres::AutoDiffCostFunction<FixedCameraReprojection, 2, 3>(
        new FixedCameraReprojection(camera, px));
  }
  Eigen::Vector2d px_;
  std::array<double, calib::kNumIntrinsics> k_;
  double r_[9], t_[3];
};

// Reprojection in a camera whose pose is adjusted: rotation q (cam_from_world, Eigen order
// x, y, z, w) and centre c in the world; p_in_cam = R (p - c). With a `base` the centre is
// base + length * u, u on the unit sphere (the scale-holding camera).
struct MovingCameraReprojection {
  template <typename T>
  bool operator()(const T* q, const T* c, const T* p, T* residual) const {
    T centre[3];
    for (int i = 0; i < 3; ++i) centre[i] = scaled_ ? T(base_[i]) + T(length_) * c[i] : c[i];
    const T d[3] = {p[0] - centre[0], p[1] - centre[1], p[2] - centre[2]};
    const T wxyz[4] = {q[3], q[0], q[1], q[2]};
    T pc[3], k[calib::kNumIntrinsics], pixel[2];
    ceres::QuaternionRotatePoint(wxyz, d, pc);
    for (int i = 0; i < calib::kNumIntrinsics; ++i) k[i] = T(k_[i]);
    if (!calib::ProjectPoint(k, pc, pixel)) return false;
    residual[0] = pixel[0] - T(px_.x());
    residual[1] = pixel[1] - T(px_.y());
    return true;
  }
  // Residual block of size 2 on the rotation (4), the centre (3) and the point (3).
  static ceres::CostFunction* Create(const MovingCameraReprojection& functor) {
    return new ceres::AutoDiffCostFunction<MovingCameraReprojection, 2, 4, 3, 3>(
        new MovingCameraReprojection(functor));
  }
  Eigen::Vector2d px_;
  std::array<double, calib::kNumIntrinsics> k_;
  bool scaled_ = false;
  Eigen::Vector3d base_ = Eigen::Vector3d::Zero();
  double length_ = 0.0;
};

// Link-length prior of two adjacent knots a and b: (|a - b| - length) / sigma (length, sigma
// in m).
struct LinkLengthPrior {
  template <typename T>
  bool operator()(const T* a, const T* b, T* residual) const {
    const T dx = a[0] - b[0], dy = a[1] - b[1], dz = a[2] - b[2];
    residual[0] = (ceres::sqrt(dx * dx + dy * dy + dz * dz) - T(length_)) / T(sigma_);
    return true;
  }
  // Residual block of size 1 on the two points (3 each).
  static ceres::CostFunction* Create(double length_m, double sigma_m) {
    return new ceres::AutoDiffCostFunction<LinkLengthPrior, 1, 3, 3>(
        new LinkLengthPrior{length_m, sigma_m});
  }
  double length_, sigma_;
};

// Smoothness prior of one knot in three consecutive frames: (a - 2 b + c) / sigma (sigma in m).
struct SmoothnessPrior {
  template <typename T>
  bool operator()(const T* a, const T* b, const T* c, T* residual) const {
    for (int i = 0; i < 3; ++i) residual[i] = (a[i] - T(2) * b[i] + c[i]) / T(sigma_);
    return true;
  }
  // Residual block of size 3 on the three points (3 each).
  static ceres::CostFunction* Create(double sigma_m) {
    return new ceres::AutoDiffCostFunction<SmoothnessPrior, 3, 3, 3, 3>(
        new SmoothnessPrior{sigma_m});
  }
  double sigma_;
};

}  // namespace netlab::recon
