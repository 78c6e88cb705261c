#pragma once
// Rotations of rod segments.
//
// Convention (stated once, here): quaternions are Eigen's, built in (w, x, y, z) constructor order
// and stored x, y, z, w (Eigen::Quaterniond::coeffs()). A segment's orientation q maps body
// (material) coordinates to world coordinates: p_in_world = q * p_in_body. The material directors
// are d1 = q e_x, d2 = q e_y and d3 = q e_z; d3 is the segment's tangent when the rod is
// unsheared (paper section 2, Fig. 1). Angular velocities of segments are body-frame vectors:
// q(t + dt) = q(t) * Exp(omega_body * dt).
//
// Relative rotations between adjacent segments use the logarithm map (rotation vector), so the
// discrete bending energy is exactly quadratic in the turning angle: a rod under an end moment
// M = 2 pi EI / L closes into a regular polygon whatever the segment count.

#include <cmath>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace netlab::netsim {

using Eigen::Quaterniond;
using Eigen::Vector3d;

// d3 = q e_z, without forming the rotation matrix.
inline Vector3d Director3(const Quaterniond& q) {
  const double x = q.x(), y = q.y(), z = q.z(), w = q.w();
  return {2.0 * (x * z + w * y), 2.0 * (y * z - w * x), 1.0 - 2.0 * (x * x + y * y)};
}

// Exp of a rotation vector phi (rad): the unit quaternion rotating by |phi| about phi / |phi|.
// Uses a Taylor series for small angles, where sin(h)/h loses precision.
inline Quaterniond ExpMap(const Vector3d& phi) {
  const double half = 0.5 * phi.norm();
  double sinc_half, cos_half;  // sin(half)/|phi| and cos(half)
  if (half < 1e-2) {
    const double h2 = half * half;
    sinc_half = 0.5 * (1.0 - h2 / 6.0 + h2 * h2 / 120.0);
    cos_half = 1.0 - h2 / 2.0 + h2 * h2 / 24.0;
  } else {
    sinc_half = std::sin(half) / (2.0 * half);
    cos_half = std::cos(half);
  }
  return Quaterniond(cos_half, sinc_half * phi.x(), sinc_half * phi.y(), sinc_half * phi.z());
}

// The logarithm map of a unit quaternion and the coefficient needed for its derivatives.
struct LogResult {
  Vector3d phi;  // rotation vector (rad), |phi| <= pi (the shorter of q and -q is used)
  double b;      // (1 - (theta/2) cot(theta/2)) / theta^2, the [phi]x^2 coefficient of J^-1
};

// Log of a unit quaternion r. The derivatives follow from the SO(3) Jacobians:
//   Log(r * Exp(d)) = phi + Jr^-1(phi) d,   Log(Exp(-d) * r) = phi - Jl^-1(phi) d,
//   Jr^-1 = I + 1/2 [phi]x + b [phi]x^2,    Jl^-1 = Jr^-1^T = I - 1/2 [phi]x + b [phi]x^2.
inline LogResult LogMap(const Quaterniond& r) {
  double w = r.w();
  Vector3d v = r.vec();
  if (w < 0.0) {
    w = -w;
    v = -v;
  }
  const double s = v.norm();
  const double theta = 2.0 * std::atan2(s, w);
  LogResult out;
  if (theta < 1e-2) {
    const double t2 = theta * theta;
    // theta / s = 2 atan(s/w)/s, series in s/w; at theta < 1e-2, w > 0.99999.
    const double u = s / w;
    out.phi = (2.0 / w) * (1.0 - u * u / 3.0 + u * u * u * u / 5.0) * v;
    out.b = 1.0 / 12.0 + t2 / 720.0;
  } else {
    out.phi = (theta / s) * v;
    out.b = (1.0 - 0.5 * theta * (w / s)) / (theta * theta);
  }
  return out;
}

// Jr^-1(phi) y and Jl^-1(phi) y, without forming matrices.
inline Vector3d ApplyJrInv(const LogResult& log, const Vector3d& y) {
  const Vector3d c = log.phi.cross(y);
  return y + 0.5 * c + log.b * log.phi.cross(c);
}
inline Vector3d ApplyJlInv(const LogResult& log, const Vector3d& y) {
  const Vector3d c = log.phi.cross(y);
  return y - 0.5 * c + log.b * log.phi.cross(c);
}

// The minimal rotation taking unit vector a to unit vector b (parallel transport of a frame).
inline Quaterniond MinimalRotation(const Vector3d& a, const Vector3d& b) {
  return Quaterniond::FromTwoVectors(a, b);
}

// An orthonormal frame with d3 = tangent. d1 is the first of the world axes y, z, x that is not
// nearly parallel to the tangent, made orthogonal: a rod along +x gets d1 = y, d2 = z, d3 = x,
// the pendulum's frame in paper section 3.
inline Quaterniond FrameFromTangent(const Vector3d& tangent) {
  const Vector3d t = tangent.normalized();
  Vector3d ref = Vector3d::UnitY();
  if (std::abs(t.dot(ref)) > 0.9) ref = Vector3d::UnitZ();
  const Vector3d d1 = (ref - ref.dot(t) * t).normalized();
  const Vector3d d2 = t.cross(d1);
  Eigen::Matrix3d r;
  r.col(0) = d1;
  r.col(1) = d2;
  r.col(2) = t;
  return Quaterniond(r).normalized();
}

}  // namespace netlab::netsim
