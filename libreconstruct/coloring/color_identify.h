#pragma once
// Knot identity from yarn colours: the codebook of a net's knots (their link colours) and the
// identification of one knot in a demosaiced frame from the colours of its 2-4 yarns. The colour
// science (sRGB, CIE XYZ, CIELAB, CIEDE2000, the colour conventions) is in colour_science.h, the
// physical palette (dyes, lighting, ChoosePalette) in palette.h; both come with this header.
//
// A wrong identity is the worst outcome. IdentifyKnot therefore reports kIdentified only when
// every plausible reading of every yarn colour leads to the same single knot of the codebook;
// otherwise kAmbiguous (all knots that fit some plausible reading) or kUnknown (none fits). In
// addition at least one yarn must be read with certainty, and the best readings of the read yarns
// must themselves be that knot's code. Thin threads on a Bayer sensor: a yarn whose image runs
// within ~9 degrees of the pixel rows or columns is not read at all (the mosaic may never sample
// one of its colours; see IdentifyOptions::bayer).

#include <Eigen/Core>
#include <array>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

#include "libreconstruct/coloring/colour.h"
#include "libreconstruct/coloring/colour_science.h"
#include "libreconstruct/coloring/net_coloring.h"
#include "libreconstruct/coloring/palette.h"
#include "libreconstruct/recording/bayer.h"

namespace netlab::recon {

// How the colours of a knot's links identify it: CodeRule of net_coloring.h (set, multiset,
// cyclic up to rotation and mirror; the degree must match too).

struct PaletteColour {
  std::string name;
  Colour linear_bgr{0, 0, 0};  // as the cameras see the yarn (fully covered pixel)
};

struct CodebookKnot {
  int row = 0, col = 0;           // grid position in the net
  std::vector<int> link_colours;  // palette indices, in cyclic order around the knot (2-4)
  int degree() const { return static_cast<int>(link_colours.size()); }
};

struct KnotCodebook {
  std::vector<PaletteColour> palette;
  std::vector<CodebookKnot> knots;
  CodeRule rule = CodeRule::kSet;

  // True when `observed` (palette indices in the cyclic order of the yarns) is the code of
  // knot `knot` under `rule` (same degree).
  bool Matches(int knot, const std::vector<int>& observed) const;
  // True when some choice of one plausible palette index per yarn (`plausible[i]`: yarn i's, in
  // cyclic order, as many yarns as the knot has links) is the code of `knot`.
  bool FitsSomeReading(int knot, const std::vector<std::vector<int>>& plausible) const;
  // The pairs of knots (i < j) whose codes are equal under the rule: not unique globally.
  std::vector<std::pair<int, int>> Collisions() const;
  // A codebook with only the given knots (e.g. those tracking predicts near a detection), so
  // uniqueness is local. Indices outside the range throw std::out_of_range.
  KnotCodebook Restrict(const std::vector<int>& knot_indices) const;
  // Palette indices in range, degrees 2..4, a non-empty palette; else false with the reason.
  bool IsValid(std::string* error) const;
};

struct IdentifyOptions {
  // The yarn is sampled along [inner_radius_px, outer_radius_px] from the knot centre (px): the
  // knot itself (a blob of overlapping thread ends) is skipped.
  double inner_radius_px = 3.0;
  double outer_radius_px = 16.0;
  // At each step along the yarn the pixel of most contrast against the background is taken
  // within +-search_half_width_px across it (the given direction may be off by a few degrees and
  // a 1 px thread may fall between pixel centres).
  double search_half_width_px = 1.5;
  double step_px = 1.0;
  // A sample counts as thread when its linear contrast |pixel - background| (0..1 units, RMS
  // over channels) reaches this; a yarn needs min_samples of them.
  double min_contrast = 0.04;
  int min_samples = 3;
  // The yarn colour is the mean of the best covered half of its samples (the thread covers
  // those pixels most; averaging removes the demosaicing zipper of a 1 px line).
  double keep_fraction = 0.5;
  // Classification: the palette colour c is fitted as background + alpha (c - background),
  // alpha in [alpha_min, alpha_max] the thread's coverage (or width in px), and scored by CIEDE2000
  // to the measured colour. Colour reading d_best <= max_delta_e, else "unknown colour" (all
  // palette colours remain plausible). A palette colour is plausible when its score is within
  // max(ambiguity_margin, ambiguity_ratio * d_best) of the best.
  double max_delta_e = 12.0;
  double ambiguity_margin = 8.0;
  double ambiguity_ratio = 1.0;
  // The gap is at least the ΔE00 that this many standard deviations of the measured colour make
  // (the pixel noise is estimated from the background ring, 1.4826 MAD).
  double noise_sigmas = 3.0;
  double alpha_min = 0.15;
  // Up to this: the cross-section integral of a thread wider than 1 px exceeds its colour.
  double alpha_max = 2.0;
  // The yarns of one knot have one image width: once two yarns are read with certainty, every
  // phase-averaged yarn is re-classified with its width within this factor of their median
  // (<= 0: off).
  double width_tolerance = 1.4;
  // The colour filter array the frame was demosaiced from (kNone: a full-colour sensor). A thin
  // thread that runs along a row or column of the mosaic may cover no site of red (or blue) at
  // all: that channel is then interpolated from pixels beside the thread and says nothing about
  // its colour. A red or blue channel whose sites the thread's centreline crosses fewer than
  // min_channel_sites times along the segment is treated as unobserved (any value fits), so
  // colours that differ mainly there become ambiguous instead of misread.
  BayerPattern bayer = BayerPattern::kRGGB;
  int min_channel_sites = 2;
  // A thread must cross this many px of rows and of columns along the segment (one mosaic
  // period: 2) for its colour to be the phase-averaged mean of its cross-section integrals.
  // Nearer an image axis its colour is unknown, unless read_along_mosaic: then it is read from
  // its best covered pixels with the unseen channels ignored (min_channel_sites). That reading
  // can be biased when the thread drifts across rows by about one pixel (it misread pink as
  // orange in bench_identify), hence off by default.
  double min_phase_travel_px = 2.0;
  bool read_along_mosaic = false;
  // The 8-bit image is linear light (Demosaic's output); false: sRGB-encoded.
  bool image_is_linear = true;
  // When not empty: only these codebook knots are considered (e.g. those tracking predicts
  // nearby), so uniqueness is judged among them.
  std::vector<int> candidate_knots;
  bool IsValid(std::string* error) const;
};

enum class IdentifyStatus { kIdentified, kAmbiguous, kUnknown };
std::string IdentifyStatusName(IdentifyStatus status);

struct YarnReading {
  int best = -1;                // palette index of the best fit, -1 without enough samples
  double best_delta_e = 0.0;    // its CIEDE2000 score
  double second_delta_e = 0.0;  // the runner-up's (inf with a one-colour palette)
  double confidence = 0.0;      // in [0, 1]: 0 unknown/ambiguous .. 1 clear
  std::vector<int> plausible;   // palette indices that this yarn may be (all when unknown)
  int samples = 0;              // thread samples found along the yarn
  double alpha = 0.0;           // fitted coverage (px of thread width) of the best colour
  double noise_delta_e = 0.0;   // ΔE00 of noise_sigmas standard deviations of the measurement
  std::array<bool, 3> observed{true, true, true};  // B, G, R seen on their own mosaic sites
  Colour measured{0, 0, 0};                        // mean linear BGR of the kept samples
};

struct KnotIdentification {
  IdentifyStatus status = IdentifyStatus::kUnknown;
  // kIdentified: the one knot (codebook index). kAmbiguous: every knot that fits some
  // plausible reading. kUnknown: empty.
  std::vector<int> knots;
  double confidence = 0.0;           // the smallest yarn confidence when identified, else 0
  std::vector<YarnReading> yarns;    // in the order of the given directions
  std::vector<std::string> reasons;  // human-readable, one per decision
  Colour background{0, 0, 0};        // the local background estimate, linear BGR
};

// Identifies the knot at `knot_px` of a demosaiced 8-bit BGR frame whose yarns leave it along
// `yarn_directions` (image, unit, in cyclic order around the knot, 2-4 of them). Throws
// std::invalid_argument on a frame that is not CV_8UC3, invalid options or codebook, or a
// direction count outside 2..4. A knot too near the border gives kUnknown with the reason.
KnotIdentification IdentifyKnot(const cv::Mat& bgr8, const Eigen::Vector2d& knot_px,
                                const std::vector<Eigen::Vector2d>& yarn_directions,
                                const IdentifyOptions& options, const KnotCodebook& codebook);

// Classifies one measured colour (linear BGR) seen against `background` to the palette; channels
// not `observed` are ignored (taken equal to each palette colour's). `measured_sigma`: the
// standard deviation of the measurement per channel (linear units); options.noise_sigmas of it
// widen the ambiguity gap.
YarnReading ClassifyYarnColour(const Colour& measured, const Colour& background,
                               const std::vector<PaletteColour>& palette,
                               const IdentifyOptions& options,
                               const std::array<bool, 3>& observed = {true, true, true},
                               const Colour& measured_sigma = Colour(0, 0, 0));

}  // namespace netlab::recon
