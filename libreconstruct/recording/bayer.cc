#include "libreconstruct/recording/bayer.h"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <vector>

namespace netlab::recon {
namespace {

// Colour of the top-left 2x2 block positions (row-major), BGR indices.
std::array<int, 4> BlockColors(BayerPattern p) {
  switch (p) {
    case BayerPattern::kRGGB: return {2, 1, 1, 0};
    case BayerPattern::kBGGR: return {0, 1, 1, 2};
    case BayerPattern::kGRBG: return {1, 2, 0, 1};
    case BayerPattern::kGBRG: return {1, 0, 2, 1};
    case BayerPattern::kNone: break;
  }
  return {-1, -1, -1, -1};
}

// LUT from raw values (0 .. 2^depth - 1 of the container) to 8-bit display values for colour c.
std::vector<uint8_t> MakeLut(const ColorCorrection& k, int colour, int entries) {
  std::vector<uint8_t> lut(entries);
  const double white = std::ldexp(1.0, k.bit_depth) - 1.0;
  const double scale = k.gains_bgr[colour] * 255.0 / std::max(1.0, white - k.black_level);
  for (int v = 0; v < entries; ++v)
    lut[v] = cv::saturate_cast<uint8_t>(std::lround((v - k.black_level) * scale));
  return lut;
}

// The three per-colour LUTs of a correction. Building a 16-bit one costs ~1 ms, so each thread
// keeps the last one it built (a recording uses one correction per camera).
const std::array<std::vector<uint8_t>, 3>& Luts(const ColorCorrection& k, int entries) {
  struct Cached {
    int entries = 0, bit_depth = 0;
    double black_level = 0.0;
    std::array<double, 3> gains{};
    std::array<std::vector<uint8_t>, 3> luts;
  };
  thread_local std::array<Cached, 4> cache;  // a few cameras' corrections
  thread_local int next = 0;
  for (const Cached& c : cache)
    if (c.entries == entries && c.bit_depth == k.bit_depth && c.black_level == k.black_level &&
        c.gains == k.gains_bgr)
      return c.luts;
  Cached& c = cache[next++ % cache.size()];
  c.entries = entries;
  c.bit_depth = k.bit_depth;
  c.black_level = k.black_level;
  c.gains = k.gains_bgr;
  for (int colour = 0; colour < 3; ++colour) c.luts[colour] = MakeLut(k, colour, entries);
  return c.luts;
}

// Applies the per-site LUTs: an 8-bit mosaic ready for demosaicing.
template <typename T>
cv::Mat CorrectMosaic(const cv::Mat& raw, BayerPattern pattern, const ColorCorrection& k) {
  const auto& luts = Luts(k, sizeof(T) == 1 ? 256 : 65536);
  const std::array<int, 4> colors = BlockColors(pattern);
  cv::Mat out(raw.size(), CV_8U);
  for (int y = 0; y < raw.rows; ++y) {
    const T* in = raw.ptr<T>(y);
    uint8_t* o = out.ptr<uint8_t>(y);
    const int c0 = colors[(y & 1) * 2] < 0 ? 1 : colors[(y & 1) * 2];
    const int c1 = colors[(y & 1) * 2 + 1] < 0 ? 1 : colors[(y & 1) * 2 + 1];
    const uint8_t* l0 = luts[c0].data();
    const uint8_t* l1 = luts[c1].data();
    int x = 0;
    for (; x + 1 < raw.cols; x += 2) {
      o[x] = l0[in[x]];
      o[x + 1] = l1[in[x + 1]];
    }
    if (x < raw.cols) o[x] = l0[in[x]];
  }
  return out;
}

// Half resolution from 2 x 2 blocks whose red, blue and two greens sit at block positions R, B,
// G1, G2 (row-major 0..3).
template <int R, int B, int G1, int G2>
void BinBlocks(const cv::Mat& mosaic, cv::Mat& out) {
  for (int y = 0; y < out.rows; ++y) {
    const uint8_t* rows[2] = {mosaic.ptr<uint8_t>(2 * y), mosaic.ptr<uint8_t>(2 * y + 1)};
    uint8_t* o = out.ptr<uint8_t>(y);
    for (int x = 0; x < out.cols; ++x) {
      const int r = rows[R / 2][2 * x + R % 2], b = rows[B / 2][2 * x + B % 2];
      const int g = (rows[G1 / 2][2 * x + G1 % 2] + rows[G2 / 2][2 * x + G2 % 2] + 1) >> 1;
      o[3 * x] = static_cast<uint8_t>(b);
      o[3 * x + 1] = static_cast<uint8_t>(g);
      o[3 * x + 2] = static_cast<uint8_t>(r);
    }
  }
}

cv::Mat CorrectedMosaic(const cv::Mat& raw, BayerPattern pattern, const ColorCorrection& k) {
  if (raw.depth() == CV_8U && k.identity_for_8bit()) return raw;
  if (raw.depth() == CV_8U) return CorrectMosaic<uint8_t>(raw, pattern, k);
  if (raw.depth() == CV_16U) return CorrectMosaic<uint16_t>(raw, pattern, k);
  cv::Mat converted;
  raw.convertTo(converted, CV_16U);
  return CorrectMosaic<uint16_t>(converted, pattern, k);
}

}  // namespace

bool ColorCorrection::identity_for_8bit() const {
  return bit_depth == 8 && black_level == 0.0 && gains_bgr[0] == 1.0 && gains_bgr[1] == 1.0 &&
         gains_bgr[2] == 1.0;
}

bool ParseBayerPattern(const std::string& text, BayerPattern* pattern) {
  if (text == "RGGB")
    *pattern = BayerPattern::kRGGB;
  else if (text == "BGGR")
    *pattern = BayerPattern::kBGGR;
  else if (text == "GRBG")
    *pattern = BayerPattern::kGRBG;
  else if (text == "GBRG")
    *pattern = BayerPattern::kGBRG;
  else if (text == "none")
    *pattern = BayerPattern::kNone;
  else
    return false;
  return true;
}

std::string BayerPatternName(BayerPattern pattern) {
  switch (pattern) {
    case BayerPattern::kRGGB: return "RGGB";
    case BayerPattern::kBGGR: return "BGGR";
    case BayerPattern::kGRBG: return "GRBG";
    case BayerPattern::kGBRG: return "GBRG";
    case BayerPattern::kNone: break;
  }
  return "none";
}

int OpenCvBayerCode(BayerPattern pattern) {
  switch (pattern) {
    case BayerPattern::kRGGB: return cv::COLOR_BayerBG2BGR;
    case BayerPattern::kBGGR: return cv::COLOR_BayerRG2BGR;
    case BayerPattern::kGRBG: return cv::COLOR_BayerGB2BGR;
    case BayerPattern::kGBRG: return cv::COLOR_BayerGR2BGR;
    case BayerPattern::kNone: break;
  }
  return -1;
}

int BayerColor(BayerPattern pattern, int row, int col) {
  return BlockColors(pattern)[(row & 1) * 2 + (col & 1)];
}

cv::Mat Demosaic(const cv::Mat& raw, BayerPattern pattern, const ColorCorrection& correction) {
  if (raw.channels() == 3 || pattern == BayerPattern::kNone) {
    // Already colour or mono: scale to 8 bits (no per-site colours).
    cv::Mat eight;
    if (raw.depth() == CV_8U && correction.identity_for_8bit()) {
      eight = raw;
    } else {
      const double white = std::ldexp(1.0, correction.bit_depth) - 1.0;
      const double scale = 255.0 / std::max(1.0, white - correction.black_level);
      raw.convertTo(eight, CV_8U, scale, -correction.black_level * scale);
    }
    if (eight.channels() == 3) return eight;
    cv::Mat bgr;
    cv::cvtColor(eight, bgr, cv::COLOR_GRAY2BGR);
    return bgr;
  }
  cv::Mat bgr;
  cv::cvtColor(CorrectedMosaic(raw, pattern, correction), bgr, OpenCvBayerCode(pattern));
  return bgr;
}

cv::Mat DemosaicHalf(const cv::Mat& raw, BayerPattern pattern, const ColorCorrection& correction) {
  if (raw.channels() == 3 || pattern == BayerPattern::kNone)
    return Downscale(Demosaic(raw, pattern, correction), 2);
  const cv::Mat mosaic = CorrectedMosaic(raw, pattern, correction);
  cv::Mat out(mosaic.rows / 2, mosaic.cols / 2, CV_8UC3);
  switch (pattern) {
    case BayerPattern::kRGGB: BinBlocks<0, 3, 1, 2>(mosaic, out); break;
    case BayerPattern::kBGGR: BinBlocks<3, 0, 1, 2>(mosaic, out); break;
    case BayerPattern::kGRBG: BinBlocks<1, 2, 0, 3>(mosaic, out); break;
    case BayerPattern::kGBRG: BinBlocks<2, 1, 0, 3>(mosaic, out); break;
    case BayerPattern::kNone: break;
  }
  return out;
}

cv::Mat Downscale(const cv::Mat& image, int factor) {
  if (factor <= 1) return image;
  cv::Mat out;
  cv::resize(image, out, cv::Size(image.cols / factor, image.rows / factor), 0, 0, cv::INTER_AREA);
  return out;
}

cv::Mat Mosaic(const cv::Mat& bgr, BayerPattern pattern) {
  CV_Assert(bgr.channels() == 3 && pattern != BayerPattern::kNone);
  cv::Mat out(bgr.size(), CV_MAKETYPE(bgr.depth(), 1));
  std::vector<cv::Mat> planes;
  cv::split(bgr, planes);
  for (int y = 0; y < bgr.rows; ++y)
    for (int x = 0; x < bgr.cols; ++x) {
      const int c = BayerColor(pattern, y, x);
      if (bgr.depth() == CV_8U)
        out.at<uint8_t>(y, x) = planes[c].at<uint8_t>(y, x);
      else
        out.at<uint16_t>(y, x) = planes[c].at<uint16_t>(y, x);
    }
  return out;
}

}  // namespace netlab::recon
