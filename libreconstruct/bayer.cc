#include "libreconstruct/bayer.h"

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

// Applies the per-site LUTs: an 8-bit mosaic ready for demosaicing.
template <typename T>
cv::Mat CorrectMosaic(const cv::Mat& raw, BayerPattern pattern, const ColorCorrection& k) {
  const int entries = sizeof(T) == 1 ? 256 : 65536;
  std::array<std::vector<uint8_t>, 3> luts;
  for (int c = 0; c < 3; ++c) luts[c] = MakeLut(k, c, entries);
  const std::array<int, 4> colors = BlockColors(pattern);
  cv::Mat out(raw.size(), CV_8U);
  cv::parallel_for_(cv::Range(0, raw.rows), [&](const cv::Range& rows) {
    for (int y = rows.start; y < rows.end; ++y) {
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
  });
  return out;
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
  if (text == "RGGB") *pattern = BayerPattern::kRGGB;
  else if (text == "BGGR") *pattern = BayerPattern::kBGGR;
  else if (text == "GRBG") *pattern = BayerPattern::kGRBG;
  else if (text == "GBRG") *pattern = BayerPattern::kGBRG;
  else if (text == "none") *pattern = BayerPattern::kNone;
  else return false;
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
  const std::array<int, 4> colors = BlockColors(pattern);
  cv::Mat out(mosaic.rows / 2, mosaic.cols / 2, CV_8UC3);
  cv::parallel_for_(cv::Range(0, out.rows), [&](const cv::Range& rows) {
    for (int y = rows.start; y < rows.end; ++y) {
      const uint8_t* r0 = mosaic.ptr<uint8_t>(2 * y);
      const uint8_t* r1 = mosaic.ptr<uint8_t>(2 * y + 1);
      cv::Vec3b* o = out.ptr<cv::Vec3b>(y);
      for (int x = 0; x < out.cols; ++x) {
        const int v[4] = {r0[2 * x], r0[2 * x + 1], r1[2 * x], r1[2 * x + 1]};
        int sum[3] = {0, 0, 0}, count[3] = {0, 0, 0};
        for (int k = 0; k < 4; ++k) {
          sum[colors[k]] += v[k];
          ++count[colors[k]];
        }
        o[x] = cv::Vec3b(static_cast<uint8_t>(sum[0] / count[0]),
                         static_cast<uint8_t>(sum[1] / count[1]),
                         static_cast<uint8_t>(sum[2] / count[2]));
      }
    }
  });
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
