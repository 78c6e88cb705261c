#include "libreconstruct/labeling/label_setup.h"

namespace netlab::recon {

LabelingSetup SetUpLabeling(const LabelingNet& net) {
  LabelingSetup setup;
  setup.options.link_length_m = net.link_length_m;
  if (net.knotless) setup.options.edge_colour_step_px = kKnotlessEdgeColourStepPx;
  if (net.coloring) {
    Lighting lighting;  // as netlab render lights the yarns
    lighting.exposure = net.illumination;
    setup.codebook = CodebookFromColoring(*net.coloring, net.dyes, lighting);
    setup.identity.identify.bayer = net.bayer;
  }
  return setup;
}

}  // namespace netlab::recon
