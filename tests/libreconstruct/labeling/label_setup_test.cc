#include "libreconstruct/labeling/label_setup.h"

#include <gtest/gtest.h>

#include <array>
#include <stdexcept>
#include <vector>

#include "libreconstruct/coloring/colour_science.h"

namespace netlab::recon {
namespace {

NetColoring SmallColoring() {
  ColoringOptions options;
  options.rule = CodeRule::kMultiset;
  options.time_limit_s = 5;
  NetColoring coloring = SolveColoring(3, 4, options);
  coloring.palette_names.clear();
  return coloring;
}

TEST(SetUpLabeling, AKnottedNetWithoutColouringHasTheEngineDefaultsAndNoColourCheck) {
  LabelingNet net;
  net.link_length_m = 0.1;
  const LabelingSetup setup = SetUpLabeling(net);
  EXPECT_EQ(setup.options.link_length_m, 0.1);
  EXPECT_EQ(setup.options.edge_colour_step_px, LabelEngineOptions{}.edge_colour_step_px);
  EXPECT_EQ(setup.options.place_sigma_px, LabelEngineOptions{}.place_sigma_px);
  EXPECT_FALSE(setup.codebook.has_value());
  EXPECT_EQ(setup.identity.identify.bayer, IdentityCheckOptions{}.identify.bayer);
}

TEST(SetUpLabeling, AKnotlessNetChecksItsEdgeKnotsColourChange) {
  LabelingNet net;
  net.knotless = true;
  const LabelingSetup setup = SetUpLabeling(net);
  EXPECT_EQ(setup.options.edge_colour_step_px, kKnotlessEdgeColourStepPx);
  EXPECT_EQ(kKnotlessEdgeColourStepPx, 1.0);
  EXPECT_EQ(setup.options.link_length_m, 0.0);  // estimated from the first frame
}

TEST(SetUpLabeling, TheColourCheckIsTheCodebookLitAtTheIlluminationReadThroughTheCamerasMosaic) {
  const NetColoring coloring = SmallColoring();
  ASSERT_GT(coloring.colors, 1);
  LabelingNet net;
  net.coloring = &coloring;
  net.dyes = {{240, 120, 20}};
  net.bayer = BayerPattern::kGBRG;
  const LabelingSetup setup = SetUpLabeling(net);
  ASSERT_TRUE(setup.codebook.has_value());
  EXPECT_EQ(setup.identity.identify.bayer, BayerPattern::kGBRG);
  // netlab render's lights unless told otherwise: the codebook CodebookFromColoring makes.
  EXPECT_EQ(kRenderIllumination, 0.85);
  Lighting lighting;
  lighting.exposure = kRenderIllumination;
  const KnotCodebook expected = CodebookFromColoring(coloring, net.dyes, lighting);
  ASSERT_EQ(setup.codebook->palette.size(), expected.palette.size());
  for (size_t i = 0; i < expected.palette.size(); ++i)
    EXPECT_EQ(setup.codebook->palette[i].linear_bgr, expected.palette[i].linear_bgr) << i;
  ASSERT_EQ(setup.codebook->knots.size(), expected.knots.size());
  for (size_t k = 0; k < expected.knots.size(); ++k)
    EXPECT_EQ(setup.codebook->knots[k].link_colours, expected.knots[k].link_colours) << k;

  net.illumination = 0.5;
  const LabelingSetup dimmer = SetUpLabeling(net);
  const Colour dye = 0.5f * SrgbToLinearBgr({240, 120, 20});
  EXPECT_LT(cv::norm(dimmer.codebook->palette[0].linear_bgr - dye), 1e-6);
}

TEST(SetUpLabeling, AnIlluminationThatIsNoExposureIsRefused) {
  const NetColoring coloring = SmallColoring();
  LabelingNet net;
  net.coloring = &coloring;
  net.illumination = -1.0;
  EXPECT_THROW(SetUpLabeling(net), std::invalid_argument);
}

}  // namespace
}  // namespace netlab::recon
