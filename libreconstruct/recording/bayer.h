#pragma once
// Single-sensor colour (Bayer mosaics): patterns, demosaicing, black level and white balance.
//
// A pattern is named by the colours of the 2 x 2 block at the top-left pixel, row by row: RGGB
// has R at (0, 0), G at (0, 1) and (1, 0), B at (1, 1). OpenCV names its conversion codes by the
// block one row and one column further in, so RGGB demosaics with cv::COLOR_BayerBG2BGR
// (OpenCvBayerCode; checked against synthetic mosaics in bayer_test.cc).

#include <array>
#include <opencv2/core.hpp>
#include <string>

namespace netlab::recon {

enum class BayerPattern { kNone, kRGGB, kBGGR, kGRBG, kGBRG };

// "RGGB", "BGGR", "GRBG", "GBRG" or "none"; false on anything else.
bool ParseBayerPattern(const std::string& text, BayerPattern* pattern);
std::string BayerPatternName(BayerPattern pattern);
// The cv::COLOR_Bayer??2BGR code that demosaics `pattern` (-1 for kNone).
int OpenCvBayerCode(BayerPattern pattern);
// Colour of pixel (row, col) of the mosaic: 0 blue, 1 green, 2 red (BGR order); -1 for kNone.
int BayerColor(BayerPattern pattern, int row, int col);

// Raw value -> display value: v8 = clamp((raw - black_level) * gain[colour] * 255 / (white -
// black_level)), white = 2^bit_depth - 1. Applied to the mosaic before demosaicing, as a lookup
// table per colour site.
struct ColorCorrection {
  int bit_depth = 8;         // significant bits of the raw values (8, 10, 12 or 16)
  double black_level = 0.0;  // raw units
  std::array<double, 3> gains_bgr = {1.0, 1.0, 1.0};  // white balance
  bool identity_for_8bit() const;
};

// A full-resolution 8-bit BGR image of a raw frame: colour correction, then bilinear demosaicing.
// A frame that is already colour (3 channels) or mono (kNone) is only colour-corrected/scaled.
cv::Mat Demosaic(const cv::Mat& raw, BayerPattern pattern, const ColorCorrection& correction);

// A half-resolution 8-bit BGR image straight from the mosaic: each 2 x 2 Bayer block becomes one
// pixel (its red, blue and the rounded mean of its greens), no interpolation: the fast display
// path.
cv::Mat DemosaicHalf(const cv::Mat& raw, BayerPattern pattern, const ColorCorrection& correction);

// Area downscaling by an integer factor (1: the image itself).
cv::Mat Downscale(const cv::Mat& image, int factor);

// The mosaic a Bayer sensor of `pattern` records of a BGR image (same depth): tests and the
// renderer.
cv::Mat Mosaic(const cv::Mat& bgr, BayerPattern pattern);

}  // namespace netlab::recon
