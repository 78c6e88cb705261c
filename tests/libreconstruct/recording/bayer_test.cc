#include "libreconstruct/recording/bayer.h"

#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>
#include <string>
#include <vector>

namespace netlab::recon {
namespace {

constexpr BayerPattern kAllPatterns[] = {BayerPattern::kRGGB, BayerPattern::kBGGR,
                                         BayerPattern::kGRBG, BayerPattern::kGBRG};

// The scene: four 32 x 32 flat patches along the top (red, green, blue, a mixed colour), a
// linear gradient in every channel below them. 128 x 96, BGR.
constexpr int kWidth = 128, kHeight = 96, kPatch = 32;
const cv::Vec3b kPatchColors[4] = {{0, 0, 255}, {0, 255, 0}, {255, 0, 0}, {40, 120, 200}};
const char* const kPatchNames[4] = {"red", "green", "blue", "mixed"};

cv::Vec3b GradientAt(int y, int x) {
  return cv::Vec3b(static_cast<uint8_t>(40 + x), static_cast<uint8_t>(30 + 2 * (y - kPatch)),
                   static_cast<uint8_t>(200 - x));
}

cv::Mat Scene() {
  cv::Mat bgr(kHeight, kWidth, CV_8UC3);
  for (int y = 0; y < kHeight; ++y)
    for (int x = 0; x < kWidth; ++x)
      bgr.at<cv::Vec3b>(y, x) = y < kPatch ? kPatchColors[x / kPatch] : GradientAt(y, x);
  return bgr;
}

int MaxChannelDifference(const cv::Vec3b& a, const cv::Vec3b& b) {
  int d = 0;
  for (int c = 0; c < 3; ++c) d = std::max(d, std::abs(int(a[c]) - int(b[c])));
  return d;
}

// Largest difference from the patch colour over patch `i`'s interior (`margin` pixels in from
// its edges) of an image at 1/`scale` of the scene's resolution.
int PatchError(const cv::Mat& bgr, int i, int scale, int margin) {
  const int size = kPatch / scale;
  int worst = 0;
  for (int y = margin; y < size - margin; ++y)
    for (int x = i * size + margin; x < (i + 1) * size - margin; ++x)
      worst = std::max(worst, MaxChannelDifference(bgr.at<cv::Vec3b>(y, x), kPatchColors[i]));
  return worst;
}

TEST(BayerPattern, ColorOfEachSiteFollowsTheName) {
  // Colour indices: 0 blue, 1 green, 2 red; the name lists the 2 x 2 block row by row.
  const struct {
    BayerPattern pattern;
    int block[4];  // (0,0), (0,1), (1,0), (1,1)
  } cases[] = {{BayerPattern::kRGGB, {2, 1, 1, 0}},
               {BayerPattern::kBGGR, {0, 1, 1, 2}},
               {BayerPattern::kGRBG, {1, 2, 0, 1}},
               {BayerPattern::kGBRG, {1, 0, 2, 1}}};
  for (const auto& c : cases) {
    SCOPED_TRACE(BayerPatternName(c.pattern));
    for (int row = 0; row < 6; ++row)
      for (int col = 0; col < 6; ++col)
        EXPECT_EQ(BayerColor(c.pattern, row, col), c.block[(row % 2) * 2 + col % 2])
            << "row " << row << " col " << col;
  }
  EXPECT_EQ(BayerColor(BayerPattern::kNone, 0, 0), -1);
  EXPECT_EQ(OpenCvBayerCode(BayerPattern::kNone), -1);
}

TEST(BayerPattern, MosaicKeepsTheSiteColourOfEachPixel) {
  const cv::Mat scene = Scene();
  for (BayerPattern p : kAllPatterns) {
    SCOPED_TRACE(BayerPatternName(p));
    const cv::Mat mosaic = Mosaic(scene, p);
    ASSERT_EQ(mosaic.type(), CV_8UC1);
    ASSERT_EQ(mosaic.size(), scene.size());
    for (int y = 0; y < kHeight; ++y)
      for (int x = 0; x < kWidth; ++x)
        ASSERT_EQ(mosaic.at<uint8_t>(y, x), scene.at<cv::Vec3b>(y, x)[BayerColor(p, y, x)]);
  }
}

TEST(BayerPattern, NamesRoundTripAndUnknownNamesAreRejected) {
  for (BayerPattern p : {BayerPattern::kRGGB, BayerPattern::kBGGR, BayerPattern::kGRBG,
                         BayerPattern::kGBRG, BayerPattern::kNone}) {
    BayerPattern parsed = p == BayerPattern::kRGGB ? BayerPattern::kNone : BayerPattern::kRGGB;
    ASSERT_TRUE(ParseBayerPattern(BayerPatternName(p), &parsed)) << BayerPatternName(p);
    EXPECT_EQ(parsed, p);
  }
  EXPECT_EQ(BayerPatternName(BayerPattern::kGRBG), "GRBG");
  EXPECT_EQ(BayerPatternName(BayerPattern::kNone), "none");
  for (const std::string bad : {"RGBG", "", "RGGB ", "RGB", "mono"}) {
    BayerPattern parsed = BayerPattern::kGBRG;
    EXPECT_FALSE(ParseBayerPattern(bad, &parsed)) << "'" << bad << "'";
    EXPECT_EQ(parsed, BayerPattern::kGBRG) << "a rejected name must leave the pattern alone";
  }
}

TEST(Demosaic, RecoversFlatPatchesAndGradientsForEveryPattern) {
  const cv::Mat scene = Scene();
  for (BayerPattern p : kAllPatterns) {
    SCOPED_TRACE(BayerPatternName(p));
    const cv::Mat bgr = Demosaic(Mosaic(scene, p), p, ColorCorrection{});
    ASSERT_EQ(bgr.type(), CV_8UC3);
    ASSERT_EQ(bgr.size(), scene.size());
    for (int i = 0; i < 4; ++i) EXPECT_LE(PatchError(bgr, i, 1, 2), 1) << kPatchNames[i];
    // Bilinear interpolation reproduces a linear ramp away from its edges.
    int worst = 0;
    for (int y = kPatch + 3; y < kHeight - 3; ++y)
      for (int x = 3; x < kWidth - 3; ++x)
        worst = std::max(worst, MaxChannelDifference(bgr.at<cv::Vec3b>(y, x), GradientAt(y, x)));
    EXPECT_LE(worst, 1) << "gradient";
  }
}

TEST(Demosaic, SixteenBitMosaicAtFullDepthMatchesTheEightBitOne) {
  const cv::Mat scene = Scene();
  cv::Mat scene16;
  scene.convertTo(scene16, CV_16U, 257.0);  // 255 -> 65535
  ColorCorrection sixteen;
  sixteen.bit_depth = 16;
  for (BayerPattern p : kAllPatterns) {
    SCOPED_TRACE(BayerPatternName(p));
    const cv::Mat mosaic16 = Mosaic(scene16, p);
    ASSERT_EQ(mosaic16.type(), CV_16UC1);
    const cv::Mat expected = Demosaic(Mosaic(scene, p), p, ColorCorrection{});
    EXPECT_EQ(cv::norm(Demosaic(mosaic16, p, sixteen), expected, cv::NORM_INF), 0.0);
    const cv::Mat expected_half = DemosaicHalf(Mosaic(scene, p), p, ColorCorrection{});
    EXPECT_EQ(cv::norm(DemosaicHalf(mosaic16, p, sixteen), expected_half, cv::NORM_INF), 0.0);
  }
}

TEST(DemosaicHalf, EachBayerBlockBecomesOnePixelOfItsSiteColours) {
  const cv::Mat scene = Scene();
  for (BayerPattern p : kAllPatterns) {
    SCOPED_TRACE(BayerPatternName(p));
    const cv::Mat half = DemosaicHalf(Mosaic(scene, p), p, ColorCorrection{});
    ASSERT_EQ(half.type(), CV_8UC3);
    ASSERT_EQ(half.size(), cv::Size(kWidth / 2, kHeight / 2));
    for (int i = 0; i < 4; ++i) EXPECT_EQ(PatchError(half, i, 2, 0), 0) << kPatchNames[i];
    // Each output pixel: red and blue of their sites, the mean of the two greens.
    int worst = 0;
    for (int y = 0; y < half.rows; ++y)
      for (int x = 0; x < half.cols; ++x) {
        int sum[3] = {0, 0, 0}, count[3] = {0, 0, 0};
        for (int dy = 0; dy < 2; ++dy)
          for (int dx = 0; dx < 2; ++dx) {
            const int c = BayerColor(p, 2 * y + dy, 2 * x + dx);
            sum[c] += scene.at<cv::Vec3b>(2 * y + dy, 2 * x + dx)[c];
            ++count[c];
          }
        ASSERT_EQ(count[0], 1);
        ASSERT_EQ(count[1], 2);
        ASSERT_EQ(count[2], 1);
        const cv::Vec3b expected(sum[0], sum[1] / 2, sum[2]);
        worst = std::max(worst, MaxChannelDifference(half.at<cv::Vec3b>(y, x), expected));
      }
    EXPECT_EQ(worst, 0);
  }
}

TEST(Demosaic, TheWrongOpenCvCodeGivesWrongColours) {
  // Guards the pattern -> OpenCV code table: every other code must visibly fail on the patches,
  // and the code of the pattern with red and blue exchanged turns red into blue.
  const cv::Mat scene = Scene();
  const auto swapped = [](BayerPattern p) {
    switch (p) {
      case BayerPattern::kRGGB: return BayerPattern::kBGGR;
      case BayerPattern::kBGGR: return BayerPattern::kRGGB;
      case BayerPattern::kGRBG: return BayerPattern::kGBRG;
      default: return BayerPattern::kGRBG;
    }
  };
  for (BayerPattern p : kAllPatterns) {
    const cv::Mat mosaic = Mosaic(scene, p);
    for (BayerPattern q : kAllPatterns) {
      if (q == p) continue;
      SCOPED_TRACE("mosaic " + BayerPatternName(p) + " demosaiced as " + BayerPatternName(q));
      cv::Mat wrong;
      cv::cvtColor(mosaic, wrong, OpenCvBayerCode(q));
      int worst = 0;
      for (int i = 0; i < 4; ++i) worst = std::max(worst, PatchError(wrong, i, 1, 2));
      EXPECT_GT(worst, 100);
      if (q == swapped(p)) {
        const cv::Vec3b centre = wrong.at<cv::Vec3b>(kPatch / 2, kPatch / 2);  // the red patch
        EXPECT_EQ(centre, cv::Vec3b(255, 0, 0)) << "red should come out blue";
      }
    }
  }
}

TEST(ColorCorrection, TwelveBitRawWithBlackLevelAndWhiteBalance) {
  // v8 = (raw - 270) * gain * 255 / (4095 - 270); 4095 - 270 = 3825 = 15 * 255, so v8 = (raw -
  // 270) / 15 * gain.
  ColorCorrection k;
  k.bit_depth = 12;
  k.black_level = 270;
  k.gains_bgr = {0.4, 1.0, 2.0};
  const struct {
    uint16_t raw;
    cv::Vec3b bgr;
  } cases[] = {
      {1770, {40, 100, 200}},    // (1770 - 270) / 15 = 100
      {270, {0, 0, 0}},          // black
      {100, {0, 0, 0}},          // below black: clamped
      {4095, {102, 255, 255}},   // white; red 510 clamps
      {65535, {255, 255, 255}},  // beyond 12 bits (corrupt data): clamped
  };
  for (BayerPattern p : kAllPatterns) {
    for (const auto& c : cases) {
      SCOPED_TRACE(BayerPatternName(p) + " raw " + std::to_string(c.raw));
      const cv::Mat raw(16, 24, CV_16UC1, cv::Scalar(c.raw));
      const cv::Mat half = DemosaicHalf(raw, p, k);
      ASSERT_EQ(half.size(), cv::Size(12, 8));
      EXPECT_EQ(cv::norm(half, cv::Mat(half.size(), CV_8UC3, cv::Scalar(c.bgr)), cv::NORM_INF), 0)
          << half.at<cv::Vec3b>(0, 0);
      const cv::Mat full = Demosaic(raw, p, k);
      ASSERT_EQ(full.size(), raw.size());
      const cv::Rect interior(2, 2, raw.cols - 4, raw.rows - 4);
      EXPECT_EQ(cv::norm(full(interior), cv::Mat(interior.size(), CV_8UC3, cv::Scalar(c.bgr)),
                         cv::NORM_INF),
                0)
          << full.at<cv::Vec3b>(8, 8);
    }
  }
}

TEST(ColorCorrection, EightBitBlackLevelStretchesToFullRange) {
  ColorCorrection k;
  k.black_level = 15;  // 255 - 15 = 240: v8 = (raw - 15) * 255 / 240
  EXPECT_FALSE(k.identity_for_8bit());
  EXPECT_TRUE(ColorCorrection{}.identity_for_8bit());
  const struct {
    uint8_t raw, expected;
  } cases[] = {{15, 0}, {10, 0}, {255, 255}, {63, 51}, {111, 102}};  // 48 * 255 / 240 = 51
  for (const auto& c : cases) {
    const cv::Mat raw(8, 8, CV_8UC1, cv::Scalar(c.raw));
    const cv::Mat half = DemosaicHalf(raw, BayerPattern::kRGGB, k);
    EXPECT_EQ(half.at<cv::Vec3b>(1, 1), cv::Vec3b(c.expected, c.expected, c.expected))
        << "raw " << int(c.raw);
  }
}

TEST(ColorCorrection, MonoFramesAreScaledToEightBits) {
  ColorCorrection k;
  k.bit_depth = 12;
  k.black_level = 270;
  cv::Mat raw(4, 6, CV_16UC1, cv::Scalar(1770));
  raw.at<uint16_t>(0, 0) = 4095;
  raw.at<uint16_t>(0, 1) = 100;
  const cv::Mat bgr = Demosaic(raw, BayerPattern::kNone, k);
  ASSERT_EQ(bgr.type(), CV_8UC3);
  EXPECT_EQ(bgr.at<cv::Vec3b>(2, 3), cv::Vec3b(100, 100, 100));
  EXPECT_EQ(bgr.at<cv::Vec3b>(0, 0), cv::Vec3b(255, 255, 255));
  EXPECT_EQ(bgr.at<cv::Vec3b>(0, 1), cv::Vec3b(0, 0, 0));
  const cv::Mat half = DemosaicHalf(raw, BayerPattern::kNone, k);
  EXPECT_EQ(half.size(), cv::Size(3, 2));
  EXPECT_EQ(half.at<cv::Vec3b>(1, 2), cv::Vec3b(100, 100, 100));

  // An 8-bit colour frame without correction comes back as it is.
  const cv::Mat colour = Scene();
  EXPECT_EQ(
      cv::norm(Demosaic(colour, BayerPattern::kNone, ColorCorrection{}), colour, cv::NORM_INF), 0);
}

TEST(Downscale, FactorTwoAveragesEachBlock) {
  // Output pixel (y, x) = 10 * (3y + x) + 5; its 2 x 2 block holds that value -3, +3, -1, +1.
  cv::Mat image(4, 6, CV_8UC1);
  cv::Mat expected(2, 3, CV_8UC1);
  for (int y = 0; y < 2; ++y)
    for (int x = 0; x < 3; ++x) {
      const int v = 10 * (3 * y + x) + 5;
      expected.at<uint8_t>(y, x) = static_cast<uint8_t>(v);
      image.at<uint8_t>(2 * y, 2 * x) = static_cast<uint8_t>(v - 3);
      image.at<uint8_t>(2 * y, 2 * x + 1) = static_cast<uint8_t>(v + 3);
      image.at<uint8_t>(2 * y + 1, 2 * x) = static_cast<uint8_t>(v - 1);
      image.at<uint8_t>(2 * y + 1, 2 * x + 1) = static_cast<uint8_t>(v + 1);
    }
  const cv::Mat half = Downscale(image, 2);
  ASSERT_EQ(half.size(), expected.size());
  EXPECT_EQ(cv::norm(half, expected, cv::NORM_INF), 0) << half;

  // Colour images, channel by channel.
  std::vector<cv::Mat> planes = {image, image + 1, image * 2};
  cv::Mat bgr, half_bgr;
  cv::merge(planes, bgr);
  cv::merge(std::vector<cv::Mat>{expected, expected + 1, expected * 2}, half_bgr);
  EXPECT_EQ(cv::norm(Downscale(bgr, 2), half_bgr, cv::NORM_INF), 0);

  // Factor 1 is the image itself.
  EXPECT_EQ(Downscale(image, 1).data, image.data);
}

}  // namespace
}  // namespace netlab::recon
