#pragma once
// Rigid transforms. Named b_from_a: x_in_b = b_from_a * x_in_a = R x_in_a + t
// (docs/architecture.md, Conventions).
// The rotation is an Eigen quaternion: constructed (w, x, y, z), stored x, y, z, w.

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace netlab::calib {

struct Rigid3d {
  Eigen::Quaterniond rotation = Eigen::Quaterniond::Identity();
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();

  Rigid3d() = default;
  Rigid3d(const Eigen::Quaterniond& r, const Eigen::Vector3d& t) : rotation(r), translation(t) {}
  Rigid3d(const Eigen::Matrix3d& r, const Eigen::Vector3d& t)
      : rotation(Eigen::Quaterniond(r).normalized()), translation(t) {}

  Eigen::Vector3d operator*(const Eigen::Vector3d& p) const { return rotation * p + translation; }
  // c_from_a = c_from_b * b_from_a.
  Rigid3d operator*(const Rigid3d& b_from_a) const {
    return Rigid3d(rotation * b_from_a.rotation, rotation * b_from_a.translation + translation);
  }
  Rigid3d Inverse() const {
    const Eigen::Quaterniond inv = rotation.conjugate();
    return Rigid3d(inv, -(inv * translation));
  }
  Eigen::Matrix3d RotationMatrix() const { return rotation.toRotationMatrix(); }

  // Angle (rad) of the rotation between two transforms, and the distance of their translations.
  static double AngleBetween(const Rigid3d& a, const Rigid3d& b) {
    return a.rotation.angularDistance(b.rotation);
  }
};

}  // namespace netlab::calib
