#pragma once
// Colour science: sRGB, CIE XYZ, CIELAB and the CIEDE2000 colour difference.
//
// Colour conventions. Images and `Colour` values are linear light in BGR order, 1 = sensor white
// (render.h). The 8-bit frames of Demosaic are linear too (value * 255, no sRGB curve). Yarn dye
// colours are given as sRGB 0..255 in R, G, B order (what a colour picker shows). Lab is CIE 1976
// L*a*b* relative to a reference white given in XYZ; the default white is that of linear (1, 1, 1)
// through the sRGB primaries, i.e. D65 (IEC 61966-2-1), so a neutral camera white is Lab (100, 0,
// 0).

#include <Eigen/Core>
#include <array>

#include "libreconstruct/coloring/colour.h"

namespace netlab::recon {

struct Lab {
  double l = 0.0, a = 0.0, b = 0.0;
};

// sRGB transfer function (IEC 61966-2-1) on one channel in [0, 1], and its inverse.
double SrgbToLinear(double encoded);
double LinearToSrgb(double linear);

// sRGB 0..255 (R, G, B) -> linear BGR in [0, 1] and back (rounded, clamped).
Colour SrgbToLinearBgr(const std::array<double, 3>& srgb_rgb);
std::array<double, 3> LinearBgrToSrgb(const Colour& bgr);

// Linear BGR -> CIE XYZ (Y = 1 for white) with the sRGB primaries and D65 white (IEC 61966-2-1).
Eigen::Vector3d LinearBgrToXyz(const Colour& bgr);
// The XYZ of linear white (1, 1, 1): D65, (0.9505, 1, 1.089).
Eigen::Vector3d D65White();
// CIE 1976 L*a*b* of `xyz` relative to the white `white_xyz` (CIE 15:2004, eq. 8.1-8.4).
Lab XyzToLab(const Eigen::Vector3d& xyz, const Eigen::Vector3d& white_xyz = D65White());
Eigen::Vector3d LabToXyz(const Lab& lab, const Eigen::Vector3d& white_xyz = D65White());
// Shorthand: linear BGR -> Lab relative to D65.
Lab LinearBgrToLab(const Colour& bgr);

// CIEDE2000 colour difference, exactly as in G. Sharma, W. Wu, E. N. Dalal, "The CIEDE2000
// color-difference formula: implementation notes, supplementary test data, and mathematical
// observations", Color Res. Appl. 30(1), 2005, eq. 1-22 (hue angles in degrees, the mean hue
// and hue difference rules of eq. 10 and 14 for the 180 degree discontinuity, h = 0 when
// a' = b = 0). Parametric factors kL = kC = kH = 1 by default.
double CieDe2000(const Lab& x, const Lab& y, double k_l = 1.0, double k_c = 1.0, double k_h = 1.0);

}  // namespace netlab::recon
