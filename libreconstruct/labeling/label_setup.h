#pragma once
// The labeling engine set up for a net: the one place `netlab label` and the workstation's
// session (`netlab gui`) take their engine options and colour check from, so the two label alike.

#include <array>
#include <optional>
#include <vector>

#include "libreconstruct/coloring/color_identify.h"
#include "libreconstruct/coloring/net_coloring.h"
#include "libreconstruct/coloring/palette.h"
#include "libreconstruct/labeling/label_engine.h"
#include "libreconstruct/labeling/label_identity.h"

namespace netlab::recon {

// A knotless net's edge colour check (LabelEngineOptions::edge_colour_step_px, px): how far from
// the junction its straight pair's colour may change (docs/labeling.md).
inline constexpr double kKnotlessEdgeColourStepPx = 1.0;

// What the person says about the net and the shot.
struct LabelingNet {
  double link_length_m = 0.0;  // knot to knot; <= 0: estimated from the first frame
  bool knotless = false;       // no knot balls (Net B): edge knots by their links' colour change
  // The colour check: the net's colouring and its dyes' sRGB (ReadColoring); none: no check.
  const NetColoring* coloring = nullptr;
  std::vector<std::array<int, 3>> dyes;
  double illumination = kRenderIllumination;  // a white dye reads this of sensor white
  BayerPattern bayer = BayerPattern::kRGGB;   // the cameras' mosaic, for reading yarn colours
};

// The engine's options and, with a colouring, its colour check.
struct LabelingSetup {
  LabelEngineOptions options;
  std::optional<KnotCodebook> codebook;  // absent: no colour check
  IdentityCheckOptions identity;         // its bayer is the net's only with a codebook

  void ApplyColourCheck(LabelEngine* engine) const {
    if (codebook) engine->SetCodebook(*codebook, identity);
  }
};

// Throws std::invalid_argument as CodebookFromColoring does (an invalid illumination, a
// colouring without colours).
LabelingSetup SetUpLabeling(const LabelingNet& net);

}  // namespace netlab::recon
