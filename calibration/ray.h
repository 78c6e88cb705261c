#pragma once
// The linear equations a calibrated view puts on a world point: the ray through a pixel, as the
// direct linear transform (DLT) writes it. The calibration's metric check and the knots'
// triangulation both start from it.

#include <Eigen/Core>

#include "calibration/rig.h"

namespace netlab::calib {

// The two linear equations a view puts on a homogeneous world point X, rows x P3 - P1 and
// y P3 - P2 of its camera's [R | t] in undistorted normalised coordinates (x, y): rows * X = 0.
// False where the pixel does not undistort.
bool RayEquations(const Camera& camera, const Eigen::Vector2d& px,
                  Eigen::Matrix<double, 2, 4>* rows);

}  // namespace netlab::calib
