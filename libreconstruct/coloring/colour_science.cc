#include "libreconstruct/coloring/colour_science.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace netlab::recon {
namespace {

constexpr double kDegToRad = std::numbers::pi / 180.0;

double Clamp01(double v) { return std::clamp(v, 0.0, 1.0); }

// CIE 1976 f(t) and its inverse (CIE 15:2004, eq. 8.3 / 8.4), delta = 6/29.
double LabF(double t) {
  constexpr double kDelta = 6.0 / 29.0;
  return t > kDelta * kDelta * kDelta ? std::cbrt(t) : t / (3 * kDelta * kDelta) + 4.0 / 29.0;
}
double LabFInverse(double f) {
  constexpr double kDelta = 6.0 / 29.0;
  return f > kDelta ? f * f * f : 3 * kDelta * kDelta * (f - 4.0 / 29.0);
}

// Hue angle in degrees in [0, 360); 0 for the achromatic point (Sharma et al., eq. 4).
double HueDegrees(double b, double a_prime) {
  if (a_prime == 0.0 && b == 0.0) return 0.0;
  double h = std::atan2(b, a_prime) / kDegToRad;
  if (h < 0) h += 360.0;
  return h;
}

}  // namespace

double SrgbToLinear(double encoded) {
  return encoded <= 0.04045 ? encoded / 12.92 : std::pow((encoded + 0.055) / 1.055, 2.4);
}

double LinearToSrgb(double linear) {
  return linear <= 0.0031308 ? 12.92 * linear : 1.055 * std::pow(linear, 1.0 / 2.4) - 0.055;
}

Colour SrgbToLinearBgr(const std::array<double, 3>& srgb_rgb) {
  return Colour(static_cast<float>(SrgbToLinear(srgb_rgb[2] / 255.0)),
                static_cast<float>(SrgbToLinear(srgb_rgb[1] / 255.0)),
                static_cast<float>(SrgbToLinear(srgb_rgb[0] / 255.0)));
}

std::array<double, 3> LinearBgrToSrgb(const Colour& bgr) {
  std::array<double, 3> rgb;
  for (int c = 0; c < 3; ++c) {
    rgb[c] = std::round(255.0 * Clamp01(LinearToSrgb(Clamp01(bgr[2 - c]))));
  }
  return rgb;
}

Eigen::Vector3d LinearBgrToXyz(const Colour& bgr) {
  // IEC 61966-2-1 primaries, D65 white.
  const double r = bgr[2], g = bgr[1], b = bgr[0];
  return {0.4124564 * r + 0.3575761 * g + 0.1804375 * b,
          0.2126729 * r + 0.7151522 * g + 0.0721750 * b,
          0.0193339 * r + 0.1191920 * g + 0.9503041 * b};
}

Eigen::Vector3d D65White() { return LinearBgrToXyz(Colour(1, 1, 1)); }

Lab XyzToLab(const Eigen::Vector3d& xyz, const Eigen::Vector3d& white_xyz) {
  const double fx = LabF(xyz.x() / white_xyz.x());
  const double fy = LabF(xyz.y() / white_xyz.y());
  const double fz = LabF(xyz.z() / white_xyz.z());
  return {116.0 * fy - 16.0, 500.0 * (fx - fy), 200.0 * (fy - fz)};
}

Eigen::Vector3d LabToXyz(const Lab& lab, const Eigen::Vector3d& white_xyz) {
  const double fy = (lab.l + 16.0) / 116.0;
  const double fx = fy + lab.a / 500.0;
  const double fz = fy - lab.b / 200.0;
  return {white_xyz.x() * LabFInverse(fx), white_xyz.y() * LabFInverse(fy),
          white_xyz.z() * LabFInverse(fz)};
}

Lab LinearBgrToLab(const Colour& bgr) { return XyzToLab(LinearBgrToXyz(bgr)); }

double CieDe2000(const Lab& x, const Lab& y, double k_l, double k_c, double k_h) {
  // Eq. 2-5: C*, G, a', C', h'.
  const double c1 = std::hypot(x.a, x.b), c2 = std::hypot(y.a, y.b);
  const double c_mean = 0.5 * (c1 + c2);
  const double c_mean7 = std::pow(c_mean, 7.0);
  constexpr double k25_7 = 6103515625.0;  // 25^7
  const double g = 0.5 * (1.0 - std::sqrt(c_mean7 / (c_mean7 + k25_7)));
  const double a1p = (1.0 + g) * x.a, a2p = (1.0 + g) * y.a;
  const double c1p = std::hypot(a1p, x.b), c2p = std::hypot(a2p, y.b);
  const double h1p = HueDegrees(x.b, a1p), h2p = HueDegrees(y.b, a2p);

  // Eq. 8-11: differences; the hue difference wraps into [-180, 180], 0 for an achromatic one.
  const double dl = y.l - x.l;
  const double dc = c2p - c1p;
  double dh = 0.0;
  if (c1p * c2p != 0.0) {
    dh = h2p - h1p;
    if (dh > 180.0) dh -= 360.0;
    if (dh < -180.0) dh += 360.0;
  }
  const double dhh = 2.0 * std::sqrt(c1p * c2p) * std::sin(0.5 * dh * kDegToRad);

  // Eq. 12-22: means and weighting functions.
  const double l_mean = 0.5 * (x.l + y.l);
  const double cp_mean = 0.5 * (c1p + c2p);
  double h_mean = h1p + h2p;
  if (c1p * c2p != 0.0) {
    if (std::abs(h1p - h2p) <= 180.0) {
      h_mean = 0.5 * (h1p + h2p);
    } else if (h1p + h2p < 360.0) {
      h_mean = 0.5 * (h1p + h2p + 360.0);
    } else {
      h_mean = 0.5 * (h1p + h2p - 360.0);
    }
  }
  const double t = 1.0 - 0.17 * std::cos((h_mean - 30.0) * kDegToRad) +
                   0.24 * std::cos(2.0 * h_mean * kDegToRad) +
                   0.32 * std::cos((3.0 * h_mean + 6.0) * kDegToRad) -
                   0.20 * std::cos((4.0 * h_mean - 63.0) * kDegToRad);
  const double d_theta = 30.0 * std::exp(-std::pow((h_mean - 275.0) / 25.0, 2.0));
  const double cp_mean7 = std::pow(cp_mean, 7.0);
  const double r_c = 2.0 * std::sqrt(cp_mean7 / (cp_mean7 + k25_7));
  const double l50 = (l_mean - 50.0) * (l_mean - 50.0);
  const double s_l = 1.0 + 0.015 * l50 / std::sqrt(20.0 + l50);
  const double s_c = 1.0 + 0.045 * cp_mean;
  const double s_h = 1.0 + 0.015 * cp_mean * t;
  const double r_t = -std::sin(2.0 * d_theta * kDegToRad) * r_c;
  const double tl = dl / (k_l * s_l), tc = dc / (k_c * s_c), th = dhh / (k_h * s_h);
  return std::sqrt(std::max(0.0, tl * tl + tc * tc + th * th + r_t * tc * th));
}

}  // namespace netlab::recon
