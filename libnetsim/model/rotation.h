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

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cmath>

namespace netlab::netsim {

using Eigen::Quaterniond;
using Eigen::Vector3d;

// d3 = q e_z, without forming the rotation matrix.
inline Vector3d Director3(const Quaterniond& q) {
  const double x = q.x(), y = q.y(), z = q.z(), w = q.w();
  return {2.0 * (x * z + w * y), 2.0 * (y * z - w * x), 1.0 - 2.0 * (x * x + y * y)};
}

// sin(|phi|/2) / |phi| and cos(|phi|/2) from h2 = (|phi|/2)^2. Small angles (every per-step
// rotation of a stable run) use a Taylor series that needs no sqrt and no trigonometry; it is exact
// to rounding below |phi| = 0.02. Reciprocal constants: a division costs ~15 cycles even by a
// constant.
inline void ExpCoefficients(double h2, double* sinc_half, double* cos_half) {
  if (h2 < 1e-4) {
    *sinc_half = 0.5 * (1.0 + h2 * (-1.0 / 6.0 + h2 * (1.0 / 120.0)));
    *cos_half = 1.0 + h2 * (-0.5 + h2 * (1.0 / 24.0));
  } else {
    const double half = std::sqrt(h2);
    *sinc_half = std::sin(half) / (2.0 * half);
    *cos_half = std::cos(half);
  }
}

// Exp of a rotation vector phi (rad): the unit quaternion rotating by |phi| about phi / |phi|.
inline Quaterniond ExpMap(const Vector3d& phi) {
  double sinc_half, cos_half;
  ExpCoefficients(0.25 * phi.squaredNorm(), &sinc_half, &cos_half);
  return Quaterniond(cos_half, sinc_half * phi.x(), sinc_half * phi.y(), sinc_half * phi.z());
}

// q <- q * Exp(phi), renormalised: the rotation update of one time step. Written on scalars (the
// same formulas as ExpMap and Eigen's product) because a temporary Quaterniond here costs a
// store-forwarding stall per segment and step.
inline void RotateBody(Quaterniond& q, const Vector3d& phi) {
  double sinc_half, cos_half;
  ExpCoefficients(0.25 * phi.squaredNorm(), &sinc_half, &cos_half);
  const double ew = cos_half, ex = sinc_half * phi.x(), ey = sinc_half * phi.y(),
               ez = sinc_half * phi.z();
  double* c = q.coeffs().data();  // x, y, z, w
  const double qx = c[0], qy = c[1], qz = c[2], qw = c[3];
  double w = qw * ew - qx * ex - qy * ey - qz * ez;
  double x = qw * ex + qx * ew + qy * ez - qz * ey;
  double y = qw * ey - qx * ez + qy * ew + qz * ex;
  double z = qw * ez + qx * ey - qy * ex + qz * ew;
  const double scale = 0.5 * (3.0 - (w * w + x * x + y * y + z * z));
  c[0] = x * scale;
  c[1] = y * scale;
  c[2] = z * scale;
  c[3] = w * scale;
}

// The logarithm map of a unit quaternion and the coefficient needed for its derivatives.
struct LogResult {
  Vector3d phi;  // rotation vector (rad), |phi| <= pi (the shorter of q and -q is used)
  double b;      // (1 - (theta/2) cot(theta/2)) / theta^2, the [phi]x^2 coefficient of J^-1
};

// Log of a unit quaternion r. The derivatives follow from the SO(3) Jacobians:
//   Log(r * Exp(d)) = phi + Jr^-1(phi) d,   Log(Exp(-d) * r) = phi - Jl^-1(phi) d,
//   Jr^-1 = I + 1/2 [phi]x + b [phi]x^2,    Jl^-1 = Jr^-1^T = I - 1/2 [phi]x + b [phi]x^2.
// The same on scalars (w, x, y, z): phi and b, for the force loops.
struct LogScalars {
  double x, y, z;  // phi, rad
  double b;
};
inline LogScalars LogMap(double w, double x, double y, double z) {
  if (w < 0.0) {
    w = -w;
    x = -x;
    y = -y;
    z = -z;
  }
  const double s2 = x * x + y * y + z * z;  // sin^2(theta/2)
  double scale, b;                          // theta / s, and b
  if (s2 < 2.5e-3) {
    // theta < 0.1 rad, nearly every joint of a resolved net: theta / s = 2 asin(s) / s as a
    // series in s^2 (error < 3e-15), which needs neither sqrt, division nor atan2. Relies on
    // |r| = 1 to rounding, which Simulation keeps by renormalising every step.
    scale = 2.0 + s2 * (1.0 / 3 + s2 * (3.0 / 20 + s2 * (5.0 / 56 + s2 * (35.0 / 576))));
    const double t2 = scale * scale * s2;  // theta^2
    b = 1.0 / 12 + t2 * (1.0 / 720 + t2 * (1.0 / 30240 + t2 * (1.0 / 1209600)));
  } else if (s2 < 0.04 * w * w) {
    // theta < 0.4: theta / s = 2 atan(u) / (u w) with u = s / w < 0.2, the series of atan(u)/u
    // to u^14 (error < u^16/17 = 4e-13), and b as its series in theta^2 (error < 1e-13).
    const double inv_w = 1.0 / w;
    const double u2 = s2 * inv_w * inv_w;
    const double atan_ratio =
        1.0 +
        u2 * (-1.0 / 3 +
              u2 * (1.0 / 5 +
                    u2 * (-1.0 / 7 +
                          u2 * (1.0 / 9 + u2 * (-1.0 / 11 + u2 * (1.0 / 13 + u2 * (-1.0 / 15)))))));
    scale = 2.0 * inv_w * atan_ratio;
    const double t2 = scale * scale * s2;  // theta^2
    b = 1.0 / 12 +
        t2 * (1.0 / 720 + t2 * (1.0 / 30240 + t2 * (1.0 / 1209600 + t2 * (1.0 / 47900160))));
  } else {
    const double s = std::sqrt(s2);
    const double theta = 2.0 * std::atan2(s, w);
    scale = theta / s;
    b = (1.0 - 0.5 * theta * (w / s)) / (theta * theta);
  }
  return {scale * x, scale * y, scale * z, b};
}

inline LogResult LogMap(const Quaterniond& r) {
  const LogScalars l = LogMap(r.w(), r.x(), r.y(), r.z());
  return {Vector3d(l.x, l.y, l.z), l.b};
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
