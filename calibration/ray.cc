#include "calibration/ray.h"

namespace netlab::calib {

bool RayEquations(const Camera& camera, const Eigen::Vector2d& px,
                  Eigen::Matrix<double, 2, 4>* rows) {
  const Eigen::Vector2d xy = UndistortPoint(camera.intrinsics, px);
  if (!xy.allFinite()) return false;
  Eigen::Matrix<double, 3, 4> p;
  p.leftCols<3>() = camera.cam_from_world.RotationMatrix();
  p.col(3) = camera.cam_from_world.translation;
  for (int j = 0; j < 2; ++j) rows->row(j) = xy[j] * p.row(2) - p.row(j);
  return true;
}

}  // namespace netlab::calib
