#include "calibration/cost_functions.h"

#include <ceres/gradient_checker.h>
#include <ceres/manifold.h>
#include <gtest/gtest.h>

#include <memory>

namespace netlab::calib {
namespace {

// The autodiff Jacobian of the reprojection functor, in the tangent spaces of the quaternion
// manifolds, agrees with numeric differentiation.
TEST(ReprojectionCostFunctor, PassesTheGradientChecker) {
  std::unique_ptr<ceres::CostFunction> cost(ReprojectionCostFunctor::Create(
      Eigen::Vector2d(1000.0, 980.0), Eigen::Vector3d(0.12, -0.05, 0.0)));
  Eigen::Quaterniond q_cw(Eigen::AngleAxisd(0.3, Eigen::Vector3d(0.2, 1.0, -0.1).normalized()));
  Eigen::Quaterniond q_wt(Eigen::AngleAxisd(-0.7, Eigen::Vector3d(1.0, 0.4, 0.3).normalized()));
  double cam_q[4] = {q_cw.x(), q_cw.y(), q_cw.z(), q_cw.w()};
  double cam_t[3] = {0.1, -0.2, 2.5};
  double intrinsics[kNumIntrinsics] = {2900,  2905,   1030,  1020, -0.1, 0.05,
                                       0.001, -0.002, -0.01, 0.0,  0.0,  0.0};
  double target_q[4] = {q_wt.x(), q_wt.y(), q_wt.z(), q_wt.w()};
  double target_t[3] = {0.3, 0.1, 0.2};
  std::vector<double*> parameters = {cam_q, cam_t, intrinsics, target_q, target_t};

  ceres::EigenQuaternionManifold quaternion;
  std::vector<const ceres::Manifold*> manifolds = {&quaternion, nullptr, nullptr, &quaternion,
                                                   nullptr};
  ceres::NumericDiffOptions numeric;
  ceres::GradientChecker checker(cost.get(), &manifolds, numeric);
  ceres::GradientChecker::ProbeResults results;
  EXPECT_TRUE(checker.Probe(parameters.data(), 1e-7, &results)) << results.error_log;
}

TEST(ReprojectionCostFunctor, ZeroResidualAtTheTruth) {
  const Eigen::Vector3d point(0.1, 0.2, 0.0);
  // Identity poses and a point 2 m ahead after a world_from_target shift.
  double cam_q[4] = {0, 0, 0, 1}, cam_t[3] = {0, 0, 0};
  double target_q[4] = {0, 0, 0, 1}, target_t[3] = {0, 0, 2.0};
  double k[kNumIntrinsics] = {1000, 1000, 500, 400, 0, 0, 0, 0, 0, 0, 0, 0};
  const Eigen::Vector2d observed(500 + 1000 * 0.1 / 2.0, 400 + 1000 * 0.2 / 2.0);
  ReprojectionCostFunctor f(observed, point);
  double r[2];
  ASSERT_TRUE(f(cam_q, cam_t, k, target_q, target_t, r));
  EXPECT_NEAR(r[0], 0.0, 1e-12);
  EXPECT_NEAR(r[1], 0.0, 1e-12);
  target_t[2] = -2.0;  // behind the camera
  EXPECT_FALSE(f(cam_q, cam_t, k, target_q, target_t, r));
}

}  // namespace
}  // namespace netlab::calib
