#pragma once
// Ceres residuals of the rig calibration, as small templated functors with a static Create()
// (after COLMAP). Each is checked against ceres::GradientChecker in cost_functions_test.cc.
//
// Parameter blocks: rotations are Eigen quaternions stored x, y, z, w (4 doubles, with
// ceres::EigenQuaternionManifold); translations 3 doubles in m; intrinsics the 12-double block of
// camera.h (fx, fy, cx, cy, k1, k2, p1, p2, k3, k4, k5, k6).

#include <ceres/autodiff_cost_function.h>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "calibration/camera.h"

namespace netlab::calib {

// Reprojection error (px) of a target point:
//   p_world = world_from_target * p_in_target,  p_cam = cam_from_world * p_world,
//   residual = Project(intrinsics, p_cam) - observed.
// A point behind the camera makes the evaluation fail (Ceres then rejects the step).
class ReprojectionCostFunctor {
 public:
  ReprojectionCostFunctor(const Eigen::Vector2d& observed, const Eigen::Vector3d& point_in_target)
      : observed_(observed), point_(point_in_target) {}

  template <typename T>
  bool operator()(const T* cam_from_world_q, const T* cam_from_world_t, const T* intrinsics,
                  const T* world_from_target_q, const T* world_from_target_t, T* residuals) const {
    const Eigen::Map<const Eigen::Quaternion<T>> q_cw(cam_from_world_q);
    const Eigen::Map<const Eigen::Matrix<T, 3, 1>> t_cw(cam_from_world_t);
    const Eigen::Map<const Eigen::Quaternion<T>> q_wt(world_from_target_q);
    const Eigen::Map<const Eigen::Matrix<T, 3, 1>> t_wt(world_from_target_t);
    const Eigen::Matrix<T, 3, 1> p_world = q_wt * point_.cast<T>() + t_wt;
    const Eigen::Matrix<T, 3, 1> p_cam = q_cw * p_world + t_cw;
    T pixel[2];
    if (!ProjectPoint(intrinsics, p_cam.data(), pixel)) return false;
    residuals[0] = pixel[0] - T(observed_.x());
    residuals[1] = pixel[1] - T(observed_.y());
    return true;
  }

  static ceres::CostFunction* Create(const Eigen::Vector2d& observed,
                                     const Eigen::Vector3d& point_in_target) {
    return new ceres::AutoDiffCostFunction<ReprojectionCostFunctor, 2, 4, 3, kNumIntrinsics, 4, 3>(
        new ReprojectionCostFunctor(observed, point_in_target));
  }

 private:
  Eigen::Vector2d observed_;
  Eigen::Vector3d point_;
};

}  // namespace netlab::calib
