#pragma once
// A stored simulation aligned to measured tracks: its knots as functions of time (cubic
// interpolation of the stored frames, with an estimate of that interpolation's error) and the
// rigid motions that carry the simulation's frame into the measured one. Shared by `netlab score`
// (score.h) and `netlab fit` (libnetsim/identification/).

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <vector>

#include "common/tracks/track_file.h"

namespace netlab::netsim {

inline Eigen::Matrix3d Skew(const Eigen::Vector3d& a) {
  Eigen::Matrix3d m;
  m << 0, -a.z(), a.y(), a.z(), 0, -a.x(), -a.y(), a.x(), 0;
  return m;
}

// The rotation of rotation vector w (axis times angle, rad).
inline Eigen::Matrix3d ExpSo3(const Eigen::Vector3d& w) {
  const double angle = w.norm();
  if (angle < 1e-12) return Eigen::Matrix3d::Identity() + Skew(w);
  return Eigen::AngleAxisd(angle, w / angle).toRotationMatrix();
}

// The stored simulation seen as a function of time: 4-point Lagrange (cubic) interpolation of the
// frames around t, its time derivative, and an estimate of its error from the 4th divided
// difference: e(t) ~ |f''''| / 24 * |prod (t - t_m)|, the interpolation remainder.
class SimInterpolant {
 public:
  SimInterpolant(const KnotTracks& sim, const std::vector<int>& sim_knot)
      : sim_(sim), sim_knot_(sim_knot) {}

  double begin() const { return sim_.time.front(); }
  double end() const { return sim_.time.back(); }

  // False when t is outside the stored span, a frame of the stencil is not valid, or (with 5 or
  // more frames) no 5 consecutive valid frames near it give the error estimate.
  // Only valid frames are read: a file may hold NaN where /knots/valid is 0 (a triangulated
  // tracks file does), and whether a point is available does not depend on asking for the error.
  bool At(double t, int k, Eigen::Vector3d* p, Eigen::Vector3d* v, double* error) const {
    const auto& s = sim_.time;
    const int n = static_cast<int>(s.size());
    const double tol = 1e-9 * std::max(1.0, std::abs(t));
    if (t < s.front() - tol || t > s.back() + tol) return false;
    int i = static_cast<int>(std::upper_bound(s.begin(), s.end(), t) - s.begin()) - 1;
    const int first = std::clamp(i - 1, 0, n - 4);
    const int ks = sim_knot_[k];
    double w[4], dw[4];
    for (int a = 0; a < 4; ++a) {
      // Lagrange basis l_a(t) and its derivative.
      double num = 1.0, den = 1.0, dnum = 0.0;
      for (int b = 0; b < 4; ++b) {
        if (b == a) continue;
        den *= s[first + a] - s[first + b];
        double prod = 1.0;
        for (int c = 0; c < 4; ++c)
          if (c != a && c != b) prod *= t - s[first + c];
        dnum += prod;
        num *= t - s[first + b];
      }
      w[a] = num / den;
      dw[a] = dnum / den;
    }
    Eigen::Vector3d pos = Eigen::Vector3d::Zero(), vel = Eigen::Vector3d::Zero();
    for (int a = 0; a < 4; ++a) {
      if (!sim_.Valid(first + a, ks)) return false;
      const Eigen::Vector3d& q = sim_.Position(first + a, ks);
      pos += w[a] * q;
      vel += dw[a] * q;
    }
    // The error's window: 5 valid frames, the stencil extended by the frame after it (before it
    // at the end of the file) where they are, else the nearest such window within kReach frames
    // (f'''' changes slowly; a knot lost now and then must not mask its neighbours' frames).
    int f5 = 0;
    if (n >= 5) {
      constexpr int kReach = 4;
      const int start = std::clamp(first, 0, n - 5);
      f5 = -1;
      for (int d = 0; d <= kReach && f5 < 0; ++d)
        for (const int candidate : {start - d, start + d}) {
          if (candidate < 0 || candidate > n - 5 || f5 >= 0) continue;
          bool valid = true;
          for (int a = 0; a < 5 && valid; ++a) valid = sim_.Valid(candidate + a, ks);
          if (valid) f5 = candidate;
        }
      if (f5 < 0) return false;
    }
    *p = pos;
    if (v) *v = vel;
    if (error) {
      // 4th divided difference over 5 frames (f''''/24), the stencil extended by one frame.
      *error = 0.0;
      if (n >= 5) {
        Eigen::Vector3d dd[5];
        for (int a = 0; a < 5; ++a) dd[a] = sim_.Position(f5 + a, ks);
        for (int level = 1; level < 5; ++level)
          for (int a = 0; a + level < 5; ++a)
            dd[a] = (dd[a + 1] - dd[a]) / (s[f5 + a + level] - s[f5 + a]);
        double prod = 1.0;
        for (int a = 0; a < 4; ++a) prod *= t - s[first + a];
        *error = dd[0].norm() * std::abs(prod);
      }
    }
    return true;
  }

 private:
  const KnotTracks& sim_;
  const std::vector<int>& sim_knot_;
};

}  // namespace netlab::netsim
