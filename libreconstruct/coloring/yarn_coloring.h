#pragma once
// The yarn colours of a net as linear colours, per link: what the renderer draws and the colour
// identity expects to read.

#include <string>
#include <vector>

#include "libreconstruct/coloring/colour.h"

namespace netlab::recon {

// The colour of each yarn link of a net: from a coloring.yaml (`netlab color-net`), or a default
// palette cycled so that neighbouring links differ.
struct YarnColoring {
  std::vector<std::string> names;  // palette names
  std::vector<Colour> palette;     // linear BGR in [0, 1]
  // Per link, in the model's link order (libnetsim/model/model.h).
  std::vector<int> link_colour;
};
YarnColoring DefaultColoring(int rows, int cols);
// The colouring of a coloring.yaml (`netlab color-net`): its dyes' sRGB as linear colours
// (without them, the default palette's colours in order). InputError on a bad file.
YarnColoring LoadYarnColoring(const std::string& path);

}  // namespace netlab::recon
