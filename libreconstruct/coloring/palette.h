#pragma once
// The physical palette: yarn dyes one can buy, how the cameras see them under the experiment's
// lighting, and the choice of the dyes that stay most distinguishable (CIEDE2000) there.

#include <Eigen/Core>
#include <array>
#include <optional>
#include <string>
#include <vector>

#include "libreconstruct/coloring/colour.h"
#include "libreconstruct/coloring/colour_science.h"

namespace netlab::recon {

// A yarn dye one can buy: its colour as sRGB 0..255 (R, G, B) under daylight.
struct Candidate {
  std::string name;
  std::array<double, 3> srgb{0, 0, 0};
};

// How brightly `netlab render` lights its scene: a white dye reads this fraction of sensor white
// (headroom below saturation). The labeling's colour check assumes it unless told otherwise.
inline constexpr double kRenderIllumination = 0.85;

// How the cameras see a dye. seen_linear_bgr = clamp(exposure * gains_bgr * linear(srgb), 0, 1)
// per channel (the sensor clips at white), then Lab relative to `white_xyz` (the camera's white;
// D65 for a white-balanced camera).
struct Lighting {
  std::array<double, 3> gains_bgr{1.0, 1.0, 1.0};  // illuminant colour / white balance error, > 0
  double exposure = 1.0;                           // brightness scale (> 0)
  Eigen::Vector3d white_xyz = D65White();          // Lab reference white (Y > 0)
  // The background the yarns are seen against, linear BGR as seen (after gains and exposure).
  // When set, every chosen colour must also differ from it by the reported minimum ΔE00.
  std::optional<Colour> background;

  // The linear BGR colour and the Lab the cameras see of an sRGB dye.
  Colour Seen(const std::array<double, 3>& srgb_rgb) const;
  Lab SeenLab(const std::array<double, 3>& srgb_rgb) const;
  bool IsValid(std::string* error) const;
};

// The indices of `k` candidates that maximise the smallest CIEDE2000 difference among them as
// seen under `lighting` (and from its background, when set). Exact (branch and bound over the
// subsets) for up to kExactPaletteCandidates candidates; otherwise greedy farthest-point
// selection improved by single swaps until no swap raises the minimum (a local optimum). Indices
// ascending. *min_delta_e (if not null) receives the achieved minimum (the pairwise and
// background differences; +inf when k == 1 without background). Throws std::invalid_argument
// when k < 1, k > candidates.size() or the lighting is invalid.
inline constexpr int kExactPaletteCandidates = 24;
std::vector<int> ChoosePalette(const std::vector<Candidate>& candidates, int k,
                               const Lighting& lighting, double* min_delta_e);
// The objective of ChoosePalette for one choice of indices.
double PaletteMinDeltaE(const std::vector<Candidate>& candidates, const std::vector<int>& chosen,
                        const Lighting& lighting);

// Reads candidates from a small text file, one per line, '#' starts a comment:
//   CSV:   red, 200, 30, 40          (an optional header line "name,r,g,b")
//   YAML:  - [red, 200, 30, 40]   or   - {name: red, r: 200, g: 30, b: 40}
// Throws std::runtime_error naming the file and line on a malformed line, a value outside
// 0..255, a duplicate name, or an unreadable / empty file.
std::vector<Candidate> LoadCandidates(const std::string& path);
// Sixteen common yarn dye colours (approximate sRGB of commercial acrylic yarns).
std::vector<Candidate> DefaultYarnCandidates();

}  // namespace netlab::recon
