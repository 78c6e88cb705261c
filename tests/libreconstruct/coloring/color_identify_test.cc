#include "libreconstruct/coloring/color_identify.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <opencv2/imgproc.hpp>
#include <stdexcept>
#include <string>
#include <vector>

#include "calibration/rig.h"
#include "libreconstruct/recording/bayer.h"
#include "libreconstruct/twin/coloured_net.h"
#include "libreconstruct/twin/render.h"

namespace netlab::recon {
namespace {

// ---------------------------------------------------------------------------------------------
// Colour science.

// Test pairs of Sharma, Wu & Dalal (2005), Table 1: Lab of both samples and the expected ΔE00.
struct SharmaPair {
  int number;
  Lab x, y;
  double delta_e;
};
const SharmaPair kSharmaPairs[] = {
    {1, {50.0000, 2.6772, -79.7751}, {50.0000, 0.0000, -82.7485}, 2.0425},
    {2, {50.0000, 3.1571, -77.2803}, {50.0000, 0.0000, -82.7485}, 2.8615},
    {3, {50.0000, 2.8361, -74.0200}, {50.0000, 0.0000, -82.7485}, 3.4412},
    {4, {50.0000, -1.3802, -84.2814}, {50.0000, 0.0000, -82.7485}, 1.0000},
    {7, {50.0000, 0.0000, 0.0000}, {50.0000, -1.0000, 2.0000}, 2.3669},
    {9, {50.0000, 2.4900, -0.0010}, {50.0000, -2.4900, 0.0009}, 7.1792},
    {11, {50.0000, 2.4900, -0.0010}, {50.0000, -2.4900, 0.0011}, 7.2195},
    {13, {50.0000, -0.0010, 2.4900}, {50.0000, 0.0009, -2.4900}, 4.8045},
    {17, {50.0000, 2.5000, 0.0000}, {73.0000, 25.0000, -18.0000}, 27.1492},
    {18, {50.0000, 2.5000, 0.0000}, {61.0000, -5.0000, 29.0000}, 22.8977},
    {19, {50.0000, 2.5000, 0.0000}, {56.0000, -27.0000, -3.0000}, 31.9030},
    {20, {50.0000, 2.5000, 0.0000}, {58.0000, 24.0000, 15.0000}, 19.4535},
    {25, {60.2574, -34.0099, 36.2677}, {60.4626, -34.1751, 39.4387}, 1.2644},
    {28, {35.0831, -44.1164, 3.7933}, {35.0232, -40.0716, 1.5901}, 1.8645},
    {30, {36.4612, 47.8580, 18.3852}, {36.2715, 50.5065, 21.2231}, 1.4146},
    {33, {6.7747, -0.2908, -2.4247}, {5.8714, -0.0985, -2.2286}, 0.6377},
    {34, {2.0776, 0.0795, -1.1350}, {0.9033, -0.0636, -0.5514}, 0.9082},
};

TEST(CieDe2000, MatchesSharmaWuDalalTestPairsToFourDecimals) {
  for (const SharmaPair& p : kSharmaPairs) {
    EXPECT_NEAR(CieDe2000(p.x, p.y), p.delta_e, 5e-5) << "pair " << p.number;
  }
}

TEST(CieDe2000, IsSymmetricAndZeroOnEqualColours) {
  for (const SharmaPair& p : kSharmaPairs) {
    EXPECT_NEAR(CieDe2000(p.x, p.y), CieDe2000(p.y, p.x), 1e-9) << "pair " << p.number;
    EXPECT_EQ(CieDe2000(p.x, p.x), 0.0);
  }
}

TEST(ColourScience, SrgbRoundTripsThroughLinearAndLab) {
  for (double v = 0; v <= 1.0; v += 0.01) {
    EXPECT_NEAR(LinearToSrgb(SrgbToLinear(v)), v, 1e-12);
  }
  // Known anchors: sRGB 0.5 is linear 0.2140; white is Lab (100, 0, 0); sRGB red (255, 0, 0)
  // is Lab (53.24, 80.09, 67.20).
  EXPECT_NEAR(SrgbToLinear(0.5), 0.21404, 1e-5);
  const Lab white = LinearBgrToLab(Colour(1, 1, 1));
  EXPECT_NEAR(white.l, 100.0, 1e-4);
  EXPECT_NEAR(white.a, 0.0, 1e-4);
  EXPECT_NEAR(white.b, 0.0, 1e-4);
  const Lab red = LinearBgrToLab(SrgbToLinearBgr({255, 0, 0}));
  EXPECT_NEAR(red.l, 53.24, 0.01);
  EXPECT_NEAR(red.a, 80.09, 0.02);
  EXPECT_NEAR(red.b, 67.20, 0.02);
  const Lab lab{40, 20, -30};
  const Lab back = XyzToLab(LabToXyz(lab));
  EXPECT_NEAR(back.l, lab.l, 1e-9);
  EXPECT_NEAR(back.a, lab.a, 1e-9);
  EXPECT_NEAR(back.b, lab.b, 1e-9);
  const std::array<double, 3> srgb{12, 200, 77};
  EXPECT_EQ(LinearBgrToSrgb(SrgbToLinearBgr(srgb)), srgb);
}

// ---------------------------------------------------------------------------------------------
// Palette.

// The best minimum over all k-subsets, by enumeration.
double BruteForceBest(const std::vector<Candidate>& candidates, int k, const Lighting& lighting) {
  const int n = static_cast<int>(candidates.size());
  double best = -1;
  for (int mask = 0; mask < (1 << n); ++mask) {
    if (__builtin_popcount(mask) != k) continue;
    std::vector<int> chosen;
    for (int i = 0; i < n; ++i) {
      if (mask & (1 << i)) chosen.push_back(i);
    }
    best = std::max(best, PaletteMinDeltaE(candidates, chosen, lighting));
  }
  return best;
}

TEST(ChoosePalette, IsExactOnSmallCandidateListsAgainstBruteForce) {
  const std::vector<Candidate> all = DefaultYarnCandidates();
  const std::vector<Candidate> small(all.begin(), all.begin() + 12);
  Lighting dark;
  dark.background = Colour(0.02f, 0.02f, 0.02f);
  Lighting shifted;
  shifted.gains_bgr = {1.3, 1.0, 0.7};
  shifted.exposure = 0.8;
  for (const Lighting& lighting : {Lighting{}, dark, shifted}) {
    for (int k : {2, 3, 5, 7}) {
      double achieved = 0;
      const std::vector<int> chosen = ChoosePalette(small, k, lighting, &achieved);
      ASSERT_EQ(static_cast<int>(chosen.size()), k);
      EXPECT_NEAR(achieved, PaletteMinDeltaE(small, chosen, lighting), 1e-12);
      EXPECT_NEAR(achieved, BruteForceBest(small, k, lighting), 1e-9) << "k = " << k;
    }
  }
}

TEST(ChoosePalette, LocalSearchOnLargeListsIsValidAndNoWorseThanAnyRandomChoice) {
  std::vector<Candidate> many;
  for (int r = 0; r < 256; r += 51) {
    for (int g = 0; g < 256; g += 85) {
      for (int b = 0; b < 256; b += 85) many.push_back({"c", {double(r), double(g), double(b)}});
    }
  }
  ASSERT_GT(static_cast<int>(many.size()), kExactPaletteCandidates);
  double achieved = 0;
  const std::vector<int> chosen = ChoosePalette(many, 8, Lighting{}, &achieved);
  ASSERT_EQ(chosen.size(), 8u);
  EXPECT_NEAR(achieved, PaletteMinDeltaE(many, chosen, Lighting{}), 1e-12);
  // Better than each of 200 random subsets (a swap local optimum of a greedy start).
  std::srand(3);
  for (int trial = 0; trial < 200; ++trial) {
    std::vector<int> pick;
    while (pick.size() < 8) {
      const int i = std::rand() % static_cast<int>(many.size());
      if (std::find(pick.begin(), pick.end(), i) == pick.end()) pick.push_back(i);
    }
    EXPECT_GE(achieved + 1e-9, PaletteMinDeltaE(many, pick, Lighting{}));
  }
}

TEST(ChoosePalette, BackgroundCountsAndMovingItAwayFromTheCandidatesRaisesTheMinimum) {
  const std::vector<Candidate> candidates = DefaultYarnCandidates();
  // Background equal to a mid red: the red dyes lose against it.
  Lighting near;
  near.background = SrgbToLinearBgr({200, 30, 40});
  double with_near = 0;
  const std::vector<int> chosen = ChoosePalette(candidates, 6, near, &with_near);
  for (int i : chosen) EXPECT_NE(candidates[i].name, "red");
  // The minimum never exceeds the chosen colours' difference from the background.
  const Lab bg = LinearBgrToLab(*near.background);
  for (int i : chosen) EXPECT_GE(CieDe2000(near.SeenLab(candidates[i].srgb), bg) + 1e-9, with_near);
  // A background far from every candidate's neighbourhood (a grey none of them is near) leaves
  // more room than one sitting on a candidate, and no background at all the most.
  Lighting none;
  double without = 0;
  ChoosePalette(candidates, 6, none, &without);
  EXPECT_GT(without, with_near);
  Lighting grey;
  grey.background = SrgbToLinearBgr({128, 128, 128});
  double with_grey = 0;
  ChoosePalette(candidates, 6, grey, &with_grey);
  EXPECT_GE(without + 1e-9, with_grey);
}

TEST(ChoosePalette, RejectsBadArguments) {
  const std::vector<Candidate> candidates = DefaultYarnCandidates();
  EXPECT_THROW(ChoosePalette(candidates, 0, Lighting{}, nullptr), std::invalid_argument);
  EXPECT_THROW(ChoosePalette(candidates, 17, Lighting{}, nullptr), std::invalid_argument);
  Lighting bad;
  bad.exposure = 0;
  EXPECT_THROW(ChoosePalette(candidates, 3, bad, nullptr), std::invalid_argument);
}

std::string WriteTemp(const std::string& name, const std::string& text) {
  const std::string path = std::string(NETLAB_BINARY_DIR) + "/" + name;
  std::ofstream(path) << text;
  return path;
}

TEST(LoadCandidates, ReadsCsvAndYamlForms) {
  const auto csv = LoadCandidates(
      WriteTemp("cand.csv", "name,r,g,b\n# dyes\nred, 200, 30, 40\n\nsky blue,110,170,230\n"));
  ASSERT_EQ(csv.size(), 2u);
  EXPECT_EQ(csv[1].name, "sky blue");
  EXPECT_EQ(csv[1].srgb[2], 230);
  const auto yaml = LoadCandidates(
      WriteTemp("cand.yaml",
                "candidates:\n  - [red, 200, 30, 40]\n  - {name: green, r: 20, g: 140, b: 60}\n"));
  ASSERT_EQ(yaml.size(), 2u);
  EXPECT_EQ(yaml[1].name, "green");
  EXPECT_EQ(yaml[1].srgb[1], 140);
}

TEST(LoadCandidates, ErrorsNameTheFileAndLine) {
  auto message = [](const std::string& text) {
    try {
      LoadCandidates(WriteTemp("bad.csv", text));
    } catch (const std::runtime_error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(message("red,1,2,3\nblue,1,2\n").find("bad.csv:2"), std::string::npos);
  EXPECT_NE(message("red,1,2,3\n\nblue,1,300,3\n").find(":3: value 300 outside"),
            std::string::npos);
  EXPECT_NE(message("red,1,x,3\n").find(":1: 'x' is not a number"), std::string::npos);
  EXPECT_NE(message("red,1,2,3\nred,4,5,6\n").find("duplicate name 'red'"), std::string::npos);
  EXPECT_NE(message("# nothing\n").find("no candidates"), std::string::npos);
  EXPECT_THROW(LoadCandidates("/nonexistent/cand.csv"), std::runtime_error);
}

// ---------------------------------------------------------------------------------------------
// Codebook rules.

TEST(KnotCodebook, RulesCompareSetsMultisetsAndCyclesUpToRotationAndMirror) {
  KnotCodebook book;
  book.palette.resize(4);
  book.knots = {{0, 0, {0, 1, 2, 3}}};
  book.rule = CodeRule::kCyclic;
  EXPECT_TRUE(book.Matches(0, {2, 3, 0, 1}));  // rotation
  EXPECT_TRUE(book.Matches(0, {3, 2, 1, 0}));  // mirror
  EXPECT_FALSE(book.Matches(0, {0, 2, 1, 3}));
  book.rule = CodeRule::kMultiset;
  EXPECT_TRUE(book.Matches(0, {0, 2, 1, 3}));
  EXPECT_FALSE(book.Matches(0, {0, 0, 1, 2}));
  book.rule = CodeRule::kSet;
  book.knots = {{0, 0, {0, 0, 1, 2}}};
  EXPECT_TRUE(book.Matches(0, {1, 2, 2, 0}));
  EXPECT_FALSE(book.Matches(0, {1, 2, 0}));  // degree differs
  const KnotCodebook two = [&] {
    KnotCodebook b = book;
    b.knots.push_back({0, 1, {2, 1, 0, 0}});
    return b;
  }();
  ASSERT_EQ(two.Collisions().size(), 1u);
  EXPECT_TRUE(two.Restrict({1}).Collisions().empty());
  EXPECT_THROW(two.Restrict({2}), std::out_of_range);
}

// ---------------------------------------------------------------------------------------------
// Identification on rendered knots.

// Six palette colours chosen from the default dyes against the dark background.
std::vector<PaletteColour> SixColourPalette(const Colour& background) {
  const std::vector<Candidate> candidates = DefaultYarnCandidates();
  Lighting lighting;
  lighting.background = background;
  const std::vector<int> chosen = ChoosePalette(candidates, 6, lighting, nullptr);
  std::vector<PaletteColour> palette;
  for (int i : chosen) palette.push_back({candidates[i].name, lighting.Seen(candidates[i].srgb)});
  return palette;
}

struct Tally {
  int correct = 0, wrong = 0, ambiguous = 0, unknown = 0;
};

// Renders `net` with the sensor (and a channel gain applied to the light before the sensor),
// then identifies each visible knot from its true pixel and yarn directions.
Tally IdentifyAll(const calib::Camera& camera, const ColouredNet& net, double noise,
                  const cv::Vec3f& gains, const IdentifyOptions& options,
                  std::vector<std::string>* failures = nullptr) {
  cv::Mat linear = RenderScene(camera, net.scene, SceneRenderOptions{});
  linear = linear.mul(cv::Scalar(gains[0], gains[1], gains[2]));
  SensorOptions sensor;
  sensor.bayer = BayerPattern::kRGGB;
  sensor.noise_sigma = noise;
  sensor.seed = 7;
  const cv::Mat frame =
      Demosaic(Expose(linear, camera.intrinsics, sensor), BayerPattern::kRGGB, ColorCorrection{});
  Tally tally;
  for (const KnotView& view : VisibleKnots(camera, net, 20)) {
    const KnotIdentification id =
        IdentifyKnot(frame, view.pixel, view.directions, options, net.codebook);
    if (std::getenv("IDENT_DEBUG")) {
      std::string text = "knot " + std::to_string(view.knot) + " true";
      for (int c : net.codebook.knots[view.knot].link_colours)
        text += " " + net.codebook.palette[c].name;
      text += " -> " + IdentifyStatusName(id.status) + ":";
      for (const std::string& r : id.reasons) text += " " + r + ";";
      std::printf("%s\n", text.c_str());
    }
    switch (id.status) {
      case IdentifyStatus::kIdentified:
        if (id.knots.size() == 1 && id.knots[0] == view.knot) {
          ++tally.correct;
        } else {
          ++tally.wrong;
          if (failures) {
            std::string text = "knot " + std::to_string(view.knot) + ":";
            for (const std::string& r : id.reasons) text += " " + r + ";";
            failures->push_back(text);
          }
        }
        break;
      case IdentifyStatus::kAmbiguous:
        ++tally.ambiguous;
        // The true knot is among those listed.
        EXPECT_NE(std::find(id.knots.begin(), id.knots.end(), view.knot), id.knots.end());
        break;
      case IdentifyStatus::kUnknown: ++tally.unknown; break;
    }
  }
  return tally;
}

class RenderedNet : public ::testing::Test {
 protected:
  void SetUp() override {
    camera_ = calib::PaperRig(0.5).cameras[0];
    const Colour background(0.02f, 0.02f, 0.02f);
    // Turned 20 deg in the image: threads along the pixel rows would leave one colour channel
    // unseen by the mosaic (that case is flagged, see AxisAlignedThreadsAreFlaggedNotMisread).
    net_ = MakeColouredNet(camera_, 4, 0.25, 1.5, 20.0 * M_PI / 180.0, 0.0005,
                           SixColourPalette(background), background, 11);
  }
  calib::Camera camera_;
  ColouredNet net_;
};

TEST_F(RenderedNet, EveryVisibleKnotIsIdentifiedOrFlaggedNeverWrongAtNoise2) {
  ASSERT_EQ(VisibleKnots(camera_, net_, 20).size(), 16u);
  std::vector<std::string> failures;
  const Tally t = IdentifyAll(camera_, net_, 2.0, {1, 1, 1}, IdentifyOptions{}, &failures);
  EXPECT_EQ(t.wrong, 0);
  for (const std::string& f : failures) ADD_FAILURE() << f;
  // At low noise nearly all are identified.
  EXPECT_GE(t.correct, 14) << t.ambiguous << " ambiguous, " << t.unknown << " unknown";
}

TEST_F(RenderedNet, NoiseAndAColourShiftFlagMoreButNeverMisidentify) {
  std::vector<std::string> failures;
  const Tally noisy = IdentifyAll(camera_, net_, 8.0, {1, 1, 1}, IdentifyOptions{}, &failures);
  EXPECT_EQ(noisy.wrong, 0);
  const Tally shifted =
      IdentifyAll(camera_, net_, 8.0, {1.3f, 1.0f, 0.7f}, IdentifyOptions{}, &failures);
  EXPECT_EQ(shifted.wrong, 0);
  for (const std::string& f : failures) ADD_FAILURE() << f;
  std::printf("noise 8: %d correct %d ambiguous %d unknown; + shift: %d / %d / %d\n", noisy.correct,
              noisy.ambiguous, noisy.unknown, shifted.correct, shifted.ambiguous, shifted.unknown);
}

TEST(RenderedAxisAlignedNet, AxisAlignedThreadsAreFlaggedNotMisread) {
  const calib::Camera camera = calib::PaperRig(0.5).cameras[0];
  const Colour background(0.02f, 0.02f, 0.02f);
  for (uint64_t seed : {11, 12}) {
    const ColouredNet net = MakeColouredNet(camera, 4, 0.25, 1.5, 0.0, 0.0005,
                                            SixColourPalette(background), background, seed);
    for (double noise : {2.0, 8.0}) {
      const Tally t = IdentifyAll(camera, net, noise, {1, 1, 1}, IdentifyOptions{});
      EXPECT_EQ(t.wrong, 0) << "seed " << seed << " noise " << noise;
    }
  }
}

TEST_F(RenderedNet, TwoKnotsSharingACodeAreAmbiguousListingBoth) {
  // Knot 5 (interior) takes knot 6's code in the codebook only: the image shows knot 5's true
  // colours, so give knot 6's entry knot 5's true code instead: two entries now fit knot 5.
  KnotCodebook book = net_.codebook;
  book.knots[6].link_colours = book.knots[5].link_colours;
  ASSERT_EQ(book.knots[5].degree(), 4);
  cv::Mat linear = RenderScene(camera_, net_.scene, SceneRenderOptions{});
  SensorOptions sensor;
  sensor.noise_sigma = 2.0;
  const cv::Mat frame =
      Demosaic(Expose(linear, camera_.intrinsics, sensor), BayerPattern::kRGGB, ColorCorrection{});
  const std::vector<KnotView> views = VisibleKnots(camera_, net_, 20);
  const KnotView& view = views[5];
  ASSERT_EQ(view.knot, 5);
  const KnotIdentification id =
      IdentifyKnot(frame, view.pixel, view.directions, IdentifyOptions{}, book);
  EXPECT_EQ(id.status, IdentifyStatus::kAmbiguous);
  EXPECT_EQ(id.knots, (std::vector<int>{5, 6}));
  // Restricted to the knots tracking predicts near it (5 and its neighbours except 6), unique.
  IdentifyOptions local;
  local.candidate_knots = {1, 4, 5, 9};
  const KnotIdentification restricted =
      IdentifyKnot(frame, view.pixel, view.directions, local, book);
  EXPECT_EQ(restricted.status, IdentifyStatus::kIdentified);
  EXPECT_EQ(restricted.knots, (std::vector<int>{5}));
}

TEST(IdentifyKnot, AnEmptyImageIsUnknownNotAGuess) {
  KnotCodebook book;
  book.palette = {{"red", {0, 0, 0.6f}}, {"green", {0, 0.5f, 0}}};
  book.knots = {{0, 0, {0, 1}}};
  const cv::Mat black(100, 100, CV_8UC3, cv::Scalar(5, 5, 5));
  const KnotIdentification id =
      IdentifyKnot(black, {50, 50}, {{1, 0}, {0, 1}}, IdentifyOptions{}, book);
  // Both yarns unreadable -> every reading plausible; one knot of degree 2 fits, but the best
  // reading does not exist: never identified from nothing.
  EXPECT_NE(id.status, IdentifyStatus::kIdentified);
  EXPECT_THROW(IdentifyKnot(black, {50, 50}, {{1, 0}}, IdentifyOptions{}, book),
               std::invalid_argument);
}

// ---------------------------------------------------------------------------------------------
// Identification on drawn (full-colour, not mosaiced) knots.

const std::vector<PaletteColour> kRgbyPalette = {{"red", {0.05f, 0.05f, 0.7f}},
                                                 {"green", {0.05f, 0.6f, 0.05f}},
                                                 {"blue", {0.7f, 0.1f, 0.02f}},
                                                 {"yellow", {0.05f, 0.6f, 0.7f}}};

TEST(ClassifyYarnColour, ClearMidwayAndForeignColours) {
  const Colour bg(0.02f, 0.02f, 0.02f);
  IdentifyOptions options;
  // A thin green thread (70 % coverage): green, with certainty.
  const YarnReading green =
      ClassifyYarnColour(bg + 0.7f * (kRgbyPalette[1].linear_bgr - bg), bg, kRgbyPalette, options);
  EXPECT_EQ(green.best, 1);
  EXPECT_EQ(green.plausible, (std::vector<int>{1}));
  EXPECT_GT(green.confidence, 0.5);
  EXPECT_NEAR(green.alpha, 0.7, 0.05);
  // Halfway between green and yellow: both plausible.
  const Colour midway = 0.5f * (kRgbyPalette[1].linear_bgr + kRgbyPalette[3].linear_bgr);
  const YarnReading mid = ClassifyYarnColour(midway, bg, kRgbyPalette, options);
  EXPECT_EQ(mid.plausible, (std::vector<int>{1, 3}));
  EXPECT_EQ(mid.confidence, 0.0);
  // Grey is none of them: unknown colour, every palette colour stays plausible.
  const YarnReading grey = ClassifyYarnColour(Colour(0.4f, 0.4f, 0.4f), bg, kRgbyPalette, options);
  EXPECT_GT(grey.best_delta_e, options.max_delta_e);
  EXPECT_EQ(grey.plausible.size(), kRgbyPalette.size());
}

// A 3-yarn knot at (100, 100) drawn with 2 px anti-aliased lines at 20, 140 and 260 degrees.
cv::Mat DrawnKnot(const std::vector<Colour>& yarn_colours, std::vector<Eigen::Vector2d>* dirs) {
  cv::Mat image(200, 200, CV_8UC3, cv::Scalar(5, 5, 5));
  dirs->clear();
  for (size_t i = 0; i < yarn_colours.size(); ++i) {
    const double a = (20.0 + 120.0 * i) * M_PI / 180.0;
    const Eigen::Vector2d d(std::cos(a), std::sin(a));
    dirs->push_back(d);
    const Colour c = yarn_colours[i] * 255.0f;
    cv::line(image, cv::Point(100, 100), cv::Point(100 + 80 * d.x(), 100 + 80 * d.y()),
             cv::Scalar(c[0], c[1], c[2]), 2, cv::LINE_AA);
  }
  return image;
}

TEST(IdentifyKnot, AnUnreadableYarnStillIdentifiesWhenEveryReadingGivesOneKnot) {
  KnotCodebook book;
  book.palette = kRgbyPalette;
  book.knots = {{0, 0, {0, 1, 2}}, {0, 1, {0, 2, 3}}};
  IdentifyOptions options;
  options.bayer = BayerPattern::kNone;
  std::vector<Eigen::Vector2d> dirs;
  // All three read: knot (0, 0) with full confidence.
  const cv::Mat clear = DrawnKnot(
      {kRgbyPalette[0].linear_bgr, kRgbyPalette[1].linear_bgr, kRgbyPalette[2].linear_bgr}, &dirs);
  const KnotIdentification a = IdentifyKnot(clear, {100, 100}, dirs, options, book);
  ASSERT_EQ(a.status, IdentifyStatus::kIdentified);
  EXPECT_EQ(a.knots, (std::vector<int>{0}));
  // The third yarn grey (no palette colour): red + green fit only knot (0, 0): identified, less
  // sure.
  const cv::Mat grey = DrawnKnot(
      {kRgbyPalette[0].linear_bgr, kRgbyPalette[1].linear_bgr, Colour(0.4f, 0.4f, 0.4f)}, &dirs);
  const KnotIdentification b = IdentifyKnot(grey, {100, 100}, dirs, options, book);
  ASSERT_EQ(b.status, IdentifyStatus::kIdentified);
  EXPECT_EQ(b.knots, (std::vector<int>{0}));
  EXPECT_LT(b.confidence, a.confidence);
  // Red + blue + grey fit both knots: ambiguous, both listed.
  const cv::Mat both = DrawnKnot(
      {kRgbyPalette[0].linear_bgr, kRgbyPalette[2].linear_bgr, Colour(0.4f, 0.4f, 0.4f)}, &dirs);
  const KnotIdentification c = IdentifyKnot(both, {100, 100}, dirs, options, book);
  EXPECT_EQ(c.status, IdentifyStatus::kAmbiguous);
  EXPECT_EQ(c.knots, (std::vector<int>{0, 1}));
}

}  // namespace
}  // namespace netlab::recon
