#include "libreconstruct/coloring/yarn_coloring.h"

#include <array>

#include "libreconstruct/coloring/color_identify.h"
#include "libreconstruct/coloring/net_coloring.h"

namespace netlab::recon {

YarnColoring DefaultColoring(int rows, int cols) {
  // Six well-separated dye colours (linear BGR). Horizontal links use the first three, vertical
  // ones the last three, each cycling along its row or column, so the links at a knot differ.
  YarnColoring c;
  c.names = {"red", "green", "blue", "yellow", "magenta", "cyan"};
  c.palette = {Colour(0.05f, 0.05f, 0.90f), Colour(0.08f, 0.75f, 0.08f),
               Colour(0.90f, 0.25f, 0.05f), Colour(0.05f, 0.80f, 0.85f),
               Colour(0.80f, 0.10f, 0.80f), Colour(0.85f, 0.75f, 0.05f)};
  const int links = rows * (cols - 1) + (rows - 1) * cols;
  const int horizontal = rows * (cols - 1);
  for (int link = 0; link < links; ++link) {
    const auto k = LinkKnots(rows, cols, link);
    c.link_colour.push_back((link < horizontal ? 0 : 3) + (k[0] + k[1]) % 3);
  }
  return c;
}

YarnColoring LoadYarnColoring(const std::string& path) {
  std::vector<std::array<int, 3>> srgb;
  const NetColoring coloring = ReadColoring(path, &srgb);
  YarnColoring yarns;
  yarns.link_colour = coloring.link_colour;
  const YarnColoring fallback = DefaultColoring(2, 2);
  for (int i = 0; i < coloring.colors; ++i) {
    yarns.names.push_back(i < static_cast<int>(coloring.palette_names.size())
                              ? coloring.palette_names[i]
                              : "colour " + std::to_string(i));
    yarns.palette.push_back(
        i < static_cast<int>(srgb.size())
            ? SrgbToLinearBgr({double(srgb[i][0]), double(srgb[i][1]), double(srgb[i][2])})
            : fallback.palette[i % fallback.palette.size()]);
  }
  return yarns;
}

}  // namespace netlab::recon
