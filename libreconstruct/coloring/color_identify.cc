#include "libreconstruct/coloring/color_identify.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>
#include <optional>
#include <set>
#include <stdexcept>
#include <utility>

namespace netlab::recon {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kDegToRad = std::numbers::pi / 180.0;

}  // namespace

bool KnotCodebook::Matches(int knot, const std::vector<int>& observed) const {
  const std::vector<int>& code = knots.at(knot).link_colours;
  if (code.size() != observed.size()) return false;
  switch (rule) {
    case CodeRule::kSet:
      return std::set<int>(code.begin(), code.end()) ==
             std::set<int>(observed.begin(), observed.end());
    case CodeRule::kMultiset: {
      std::vector<int> a = code, b = observed;
      std::sort(a.begin(), a.end());
      std::sort(b.begin(), b.end());
      return a == b;
    }
    case CodeRule::kCyclic: {
      const int n = static_cast<int>(code.size());
      for (int shift = 0; shift < n; ++shift) {
        bool forward = true, backward = true;
        for (int i = 0; i < n; ++i) {
          forward = forward && code[(i + shift) % n] == observed[i];
          backward = backward && code[(shift - i + n) % n] == observed[i];
        }
        if (forward || backward) return true;
      }
      return false;
    }
  }
  return false;
}

bool KnotCodebook::FitsSomeReading(int knot, const std::vector<std::vector<int>>& plausible) const {
  const std::vector<int>& code = knots[knot].link_colours;
  const size_t n = plausible.size();
  if (code.size() != n) return false;
  // Each yarn can only take colours the knot has; enumerate those (at most 4^4 readings).
  std::vector<std::vector<int>> options(n);
  for (size_t i = 0; i < n; ++i) {
    for (int c : plausible[i]) {
      if (std::find(code.begin(), code.end(), c) != code.end()) options[i].push_back(c);
    }
    if (options[i].empty()) return false;
  }
  std::vector<size_t> index(n, 0);
  std::vector<int> reading(n);
  while (true) {
    for (size_t i = 0; i < n; ++i) reading[i] = options[i][index[i]];
    if (Matches(knot, reading)) return true;
    size_t i = 0;
    while (i < n && ++index[i] == options[i].size()) index[i++] = 0;
    if (i == n) return false;
  }
}

std::vector<std::pair<int, int>> KnotCodebook::Collisions() const {
  std::vector<std::pair<int, int>> out;
  for (size_t i = 0; i < knots.size(); ++i) {
    for (size_t j = i + 1; j < knots.size(); ++j) {
      if (Matches(static_cast<int>(i), knots[j].link_colours)) {
        out.emplace_back(static_cast<int>(i), static_cast<int>(j));
      }
    }
  }
  return out;
}

KnotCodebook KnotCodebook::Restrict(const std::vector<int>& knot_indices) const {
  KnotCodebook out;
  out.palette = palette;
  out.rule = rule;
  for (int i : knot_indices) out.knots.push_back(knots.at(i));
  return out;
}

bool KnotCodebook::IsValid(std::string* error) const {
  auto fail = [&](const std::string& why) {
    if (error) *error = why;
    return false;
  };
  if (palette.empty()) return fail("KnotCodebook: empty palette");
  for (size_t k = 0; k < knots.size(); ++k) {
    const CodebookKnot& knot = knots[k];
    const std::string where = "KnotCodebook: knot " + std::to_string(k) + " (row " +
                              std::to_string(knot.row) + ", col " + std::to_string(knot.col) + ")";
    if (knot.degree() < 2 || knot.degree() > 4) return fail(where + ": degree not in 2..4");
    for (int c : knot.link_colours) {
      if (c < 0 || c >= static_cast<int>(palette.size())) {
        return fail(where + ": palette index " + std::to_string(c) + " out of range");
      }
    }
  }
  return true;
}

bool IdentifyOptions::IsValid(std::string* error) const {
  auto fail = [&](const std::string& why) {
    if (error) *error = "IdentifyOptions: " + why;
    return false;
  };
  if (!(inner_radius_px >= 0) || !(outer_radius_px > inner_radius_px)) {
    return fail("need 0 <= inner_radius_px < outer_radius_px");
  }
  if (!(search_half_width_px >= 0)) return fail("search_half_width_px must be >= 0");
  if (!(step_px > 0)) return fail("step_px must be > 0");
  if (!(min_contrast > 0)) return fail("min_contrast must be > 0");
  if (min_samples < 1) return fail("min_samples must be >= 1");
  if (!(keep_fraction > 0 && keep_fraction <= 1)) return fail("keep_fraction must be in (0, 1]");
  if (!(max_delta_e > 0)) return fail("max_delta_e must be > 0");
  if (!(ambiguity_margin >= 0) || !(ambiguity_ratio >= 0)) {
    return fail("ambiguity_margin and ambiguity_ratio must be >= 0");
  }
  if (!(noise_sigmas >= 0)) {
    return fail("noise_sigmas must be >= 0");
  }
  if (!(alpha_min > 0 && alpha_max >= alpha_min)) return fail("need 0 < alpha_min <= alpha_max");
  return true;
}

std::string IdentifyStatusName(IdentifyStatus status) {
  switch (status) {
    case IdentifyStatus::kIdentified: return "identified";
    case IdentifyStatus::kAmbiguous: return "ambiguous";
    case IdentifyStatus::kUnknown: return "unknown";
  }
  return "?";
}

namespace {

// The best CIEDE2000 between `measured_lab` and background + alpha (colour - background) over
// alpha in [alpha_min, 1]: a coarse grid, then golden-section refinement around its best.
double MixtureDeltaE(const Colour& measured, const Colour& colour, const Colour& background,
                     double alpha_min, double alpha_max, const std::array<bool, 3>& observed,
                     double* best_alpha) {
  const bool all = observed[0] && observed[1] && observed[2];
  const Lab measured_lab = LinearBgrToLab(measured);
  auto at = [&](double alpha) {
    const Colour mix = background + static_cast<float>(alpha) * (colour - background);
    if (all) return CieDe2000(measured_lab, LinearBgrToLab(mix));
    Colour m = measured;
    for (int c = 0; c < 3; ++c) {
      if (!observed[c]) m[c] = mix[c];
    }
    return CieDe2000(LinearBgrToLab(m), LinearBgrToLab(mix));
  };
  constexpr int kGrid = 24;
  const double step = (alpha_max - alpha_min) / kGrid;
  int best_i = 0;
  double best = kInf;
  for (int i = 0; i <= kGrid; ++i) {
    const double v = at(alpha_min + i * step);
    if (v < best) best = v, best_i = i;
  }
  double lo = alpha_min + std::max(0, best_i - 1) * step;
  double hi = alpha_min + std::min(kGrid, best_i + 1) * step;
  constexpr double kPhi = 0.6180339887498949;
  double x1 = hi - kPhi * (hi - lo), x2 = lo + kPhi * (hi - lo);
  double f1 = at(x1), f2 = at(x2);
  for (int it = 0; it < 20; ++it) {
    if (f1 < f2) {
      hi = x2, x2 = x1, f2 = f1, x1 = hi - kPhi * (hi - lo), f1 = at(x1);
    } else {
      lo = x1, x1 = x2, f1 = f2, x2 = lo + kPhi * (hi - lo), f2 = at(x2);
    }
  }
  const double grid_alpha = alpha_min + best_i * step;
  if (best <= f1 && best <= f2) {
    *best_alpha = grid_alpha;
    return best;
  }
  *best_alpha = f1 < f2 ? x1 : x2;
  return std::min(f1, f2);
}

// Linear colour of the frame at sub-pixel `p` (bilinear over linear values), false outside.
class LinearSampler {
 public:
  LinearSampler(const cv::Mat& bgr8, bool linear) : image_(bgr8) {
    for (int v = 0; v < 256; ++v) {
      lut_[v] = static_cast<float>(linear ? v / 255.0 : SrgbToLinear(v / 255.0));
    }
  }
  bool At(const Eigen::Vector2d& p, Colour* out) const {
    const double x0 = std::floor(p.x()), y0 = std::floor(p.y());
    if (!(x0 >= 0 && y0 >= 0 && x0 + 1 < image_.cols && y0 + 1 < image_.rows)) return false;
    const int x = static_cast<int>(x0), y = static_cast<int>(y0);
    const float fx = static_cast<float>(p.x() - x0), fy = static_cast<float>(p.y() - y0);
    Colour sum(0, 0, 0);
    const float w[4] = {(1 - fx) * (1 - fy), fx * (1 - fy), (1 - fx) * fy, fx * fy};
    const cv::Vec3b px[4] = {image_.at<cv::Vec3b>(y, x), image_.at<cv::Vec3b>(y, x + 1),
                             image_.at<cv::Vec3b>(y + 1, x), image_.at<cv::Vec3b>(y + 1, x + 1)};
    for (int i = 0; i < 4; ++i) {
      for (int c = 0; c < 3; ++c) sum[c] += w[i] * lut_[px[i][c]];
    }
    *out = sum;
    return true;
  }

 private:
  const cv::Mat& image_;
  float lut_[256];
};

double Contrast(const Colour& a, const Colour& b) {
  const Colour d = a - b;
  return std::sqrt((d[0] * d[0] + d[1] * d[1] + d[2] * d[2]) / 3.0);
}

// Distance of `p` from the ray knot + s * dir, s >= 0.
double RayDistance(const Eigen::Vector2d& p, const Eigen::Vector2d& knot,
                   const Eigen::Vector2d& dir) {
  const Eigen::Vector2d v = p - knot;
  const double s = std::max(0.0, v.dot(dir));
  return (v - s * dir).norm();
}

std::string KnotName(const CodebookKnot& k) {
  char name[32];  // (snprintf: GCC 12 warns falsely on "(" + std::to_string(...))
  std::snprintf(name, sizeof(name), "(%d, %d)", k.row, k.col);
  return name;
}

// Every palette index: what a yarn of unknown colour may be.
std::vector<int> AllPaletteIndices(size_t palette_size) {
  std::vector<int> all;
  for (size_t c = 0; c < palette_size; ++c) all.push_back(static_cast<int>(c));
  return all;
}

}  // namespace

YarnReading ClassifyYarnColour(const Colour& measured, const Colour& background,
                               const std::vector<PaletteColour>& palette,
                               const IdentifyOptions& options, const std::array<bool, 3>& observed,
                               const Colour& measured_sigma) {
  YarnReading r;
  // The ΔE00 that noise_sigmas standard deviations of the measurement make, per channel.
  {
    const Lab lab = LinearBgrToLab(measured);
    for (int c = 0; c < 3; ++c) {
      for (float sign : {-1.0f, 1.0f}) {
        Colour moved = measured;
        moved[c] = std::max(
            0.0f, moved[c] + sign * static_cast<float>(options.noise_sigmas) * measured_sigma[c]);
        r.noise_delta_e = std::max(r.noise_delta_e, CieDe2000(lab, LinearBgrToLab(moved)));
      }
    }
  }
  r.measured = measured;
  r.observed = observed;
  std::vector<double> score(palette.size()), alpha(palette.size());
  for (size_t c = 0; c < palette.size(); ++c) {
    score[c] = MixtureDeltaE(measured, palette[c].linear_bgr, background, options.alpha_min,
                             options.alpha_max, observed, &alpha[c]);
  }
  r.best = static_cast<int>(std::min_element(score.begin(), score.end()) - score.begin());
  r.best_delta_e = score[r.best];
  r.alpha = alpha[r.best];
  r.second_delta_e = kInf;
  for (size_t c = 0; c < palette.size(); ++c) {
    if (static_cast<int>(c) != r.best) r.second_delta_e = std::min(r.second_delta_e, score[c]);
  }
  if (r.best_delta_e > options.max_delta_e) {
    // Unknown colour: any palette colour may be behind it.
    r.plausible = AllPaletteIndices(palette.size());
    r.confidence = 0.0;
    return r;
  }
  const double gap = std::max(
      {options.ambiguity_margin, options.ambiguity_ratio * r.best_delta_e, r.noise_delta_e});
  for (size_t c = 0; c < palette.size(); ++c) {
    if (score[c] <= r.best_delta_e + gap) r.plausible.push_back(static_cast<int>(c));
  }
  if (r.plausible.size() == 1) {
    const double excess =
        std::isfinite(r.second_delta_e) ? (r.second_delta_e - r.best_delta_e) / (2.0 * gap) : 1.0;
    r.confidence =
        std::clamp(excess, 0.5, 1.0) * (1.0 - 0.5 * r.best_delta_e / options.max_delta_e);
  }
  return r;
}

namespace {

// The inputs that the steps of IdentifyKnot share.
struct KnotView {
  const LinearSampler& sampler;              // the frame, linear light
  const Eigen::Vector2d& knot_px;            // the knot's centre (px)
  const std::vector<Eigen::Vector2d>& dirs;  // its yarns' unit directions, in cyclic order
  const IdentifyOptions& options;
  const KnotCodebook& codebook;
  int yarns() const { return static_cast<int>(dirs.size()); }
};

// Checks the arguments of IdentifyKnot (std::invalid_argument naming what is wrong) and returns
// the yarn directions as unit vectors.
std::vector<Eigen::Vector2d> CheckedUnitDirections(
    const cv::Mat& bgr8, const std::vector<Eigen::Vector2d>& yarn_directions,
    const IdentifyOptions& options, const KnotCodebook& codebook) {
  std::string error;
  if (bgr8.type() != CV_8UC3) throw std::invalid_argument("IdentifyKnot: frame is not CV_8UC3");
  if (!options.IsValid(&error)) throw std::invalid_argument("IdentifyKnot: " + error);
  if (!codebook.IsValid(&error)) throw std::invalid_argument("IdentifyKnot: " + error);
  const int n = static_cast<int>(yarn_directions.size());
  if (n < 2 || n > 4) {
    throw std::invalid_argument("IdentifyKnot: " + std::to_string(n) +
                                " yarn directions (need 2..4)");
  }
  std::vector<Eigen::Vector2d> dirs;
  for (const Eigen::Vector2d& d : yarn_directions) {
    if (!(d.norm() > 1e-9) || !d.allFinite()) {
      throw std::invalid_argument("IdentifyKnot: a yarn direction is zero or not finite");
    }
    dirs.push_back(d.normalized());
  }
  for (int k : options.candidate_knots) {
    if (k < 0 || k >= static_cast<int>(codebook.knots.size())) {
      throw std::invalid_argument("IdentifyKnot: candidate knot " + std::to_string(k) +
                                  " not in the codebook");
    }
  }
  return dirs;
}

// The background around a knot and the noise of its pixels.
struct LocalBackground {
  Colour colour{0, 0, 0};       // the median per channel, linear BGR
  Colour pixel_sigma{0, 0, 0};  // 1.4826 x the median absolute deviation (a Gaussian's sigma)
};

// The local background: the median of rings around the knot away from every yarn (>= 25 deg);
// nullopt when none of them is visible.
std::optional<LocalBackground> EstimateLocalBackground(const KnotView& view) {
  const IdentifyOptions& options = view.options;
  std::vector<float> channel[3];
  const double cos_limit = std::cos(25.0 * kDegToRad);
  for (double radius = options.inner_radius_px + 2; radius <= options.outer_radius_px;
       radius += 2) {
    for (int a = 0; a < 72; ++a) {
      const Eigen::Vector2d u(std::cos(a * 5 * kDegToRad), std::sin(a * 5 * kDegToRad));
      bool clear = true;
      for (const Eigen::Vector2d& d : view.dirs) clear = clear && u.dot(d) < cos_limit;
      Colour c;
      // At pixel centres: bilinear interpolation would smooth the noise measured here.
      const Eigen::Vector2d at = (view.knot_px + radius * u).array().round().matrix();
      if (!clear || !view.sampler.At(at, &c)) continue;
      for (int k = 0; k < 3; ++k) channel[k].push_back(c[k]);
    }
  }
  if (channel[0].empty()) return std::nullopt;
  LocalBackground background;
  for (int k = 0; k < 3; ++k) {
    auto mid = channel[k].begin() + channel[k].size() / 2;
    std::nth_element(channel[k].begin(), mid, channel[k].end());
    background.colour[k] = *mid;
    // Pixel noise: 1.4826 x the median absolute deviation (a Gaussian's sigma).
    std::vector<float> deviation;
    for (float v : channel[k]) deviation.push_back(std::abs(v - background.colour[k]));
    auto dmid = deviation.begin() + deviation.size() / 2;
    std::nth_element(deviation.begin(), dmid, deviation.end());
    background.pixel_sigma[k] = 1.4826f * *dmid;
  }
  return background;
}

// The pixel of most contrast against the background on one cross-section of a yarn.
struct CrossSectionPeak {
  double contrast = -1;  // -1: no pixel of the cross-section is usable
  Colour colour;
  Eigen::Vector2d px;
};

// The most contrasted point within +-search_half_width_px across yarn y at distance r from the
// knot, among the points no nearer another yarn than 2 px (thread width and the bilinear
// footprint).
CrossSectionPeak MostContrastedAcross(const KnotView& view, int y, double r,
                                      const Colour& background) {
  const Eigen::Vector2d d = view.dirs[y], across(-d.y(), d.x());
  CrossSectionPeak peak;
  for (double t = -view.options.search_half_width_px; t <= view.options.search_half_width_px + 1e-9;
       t += 0.5) {
    const Eigen::Vector2d p = view.knot_px + r * d + t * across;
    bool own = true;
    for (int o = 0; o < view.yarns(); ++o) {
      if (o != y && RayDistance(p, view.knot_px, view.dirs[o]) < 2.0) own = false;
    }
    Colour c;
    if (!own || !view.sampler.At(p, &c)) continue;
    const double contrast = Contrast(c, background);
    if (contrast > peak.contrast) peak.contrast = contrast, peak.colour = c, peak.px = p;
  }
  return peak;
}

// What sampling along one yarn found.
struct YarnSamples {
  // (contrast, colour) of each cross-section's most contrasted point, where it is thread.
  std::vector<std::pair<double, Colour>> samples;
  // The cross-section integrals of (pixel - background) there, where inside the frame.
  std::vector<Colour> integrals;
  std::array<int, 3> sites{0, 0, 0};  // mosaic sites of each colour under the centreline
  double travel = 0.0;                // px of rows or of columns (the fewer) crossed
  bool phase_averaged = false;        // every mosaic phase seen: the integrals are unbiased
};

// Samples yarn y along [inner_radius_px, outer_radius_px] in steps of step_px.
YarnSamples SampleYarn(const KnotView& view, int y, const Colour& background) {
  const IdentifyOptions& options = view.options;
  const Eigen::Vector2d d = view.dirs[y], across(-d.y(), d.x());
  YarnSamples s;
  // A thread that crosses at least one mosaic period (2 px) of rows and of columns along the
  // segment has seen every colour site at every phase: the mean cross-section integral is an
  // unbiased colour. Else (near an image axis) the best covered samples, with the channels
  // whose sites it never crosses ignored.
  s.travel = (options.outer_radius_px - options.inner_radius_px) *
             std::min(std::abs(d.x()), std::abs(d.y()));
  s.phase_averaged =
      options.bayer == BayerPattern::kNone || s.travel >= options.min_phase_travel_px;
  for (double r = options.inner_radius_px; r <= options.outer_radius_px + 1e-9;
       r += options.step_px) {
    const CrossSectionPeak peak = MostContrastedAcross(view, y, r, background);
    if (peak.contrast >= options.min_contrast) {
      s.samples.emplace_back(peak.contrast, peak.colour);
      // The cross-section integral around the thread's centre: sum of (pixel - background)
      // over 5 px across, i.e. width x (yarn - background) for a thread narrower than that.
      Colour integral(0, 0, 0);
      bool inside = true;
      for (int t = -2; t <= 2 && inside; ++t) {
        Colour c;
        inside = view.sampler.At(peak.px + t * across, &c);
        integral += c - background;
      }
      if (inside) s.integrals.push_back(integral);
      if (options.bayer != BayerPattern::kNone) {
        const int site = BayerColor(options.bayer, static_cast<int>(std::lround(peak.px.y())),
                                    static_cast<int>(std::lround(peak.px.x())));
        if (site >= 0) ++s.sites[site];
      }
    }
  }
  return s;
}

// Why the colour of yarn y cannot be read from its samples; empty when it can.
std::string WhyColourUnread(const KnotView& view, int y, const YarnSamples& s) {
  const IdentifyOptions& options = view.options;
  if (!s.phase_averaged && !options.read_along_mosaic) {
    char text[200];
    std::snprintf(text, sizeof(text),
                  "yarn %d: runs along the pixel rows or columns (%.1f px across them over the "
                  "segment < %.1f): the mosaic does not see all its colours, colour unknown",
                  y, s.travel, options.min_phase_travel_px);
    return text;
  }
  if (static_cast<int>(s.samples.size()) < options.min_samples) {
    return "yarn " + std::to_string(y) + ": only " + std::to_string(s.samples.size()) +
           " thread samples (need " + std::to_string(options.min_samples) + "): colour unknown";
  }
  return "";
}

// A yarn whose colour was measured, to be classified once all yarns are (their widths agree).
struct MeasuredYarn {
  int y;
  Colour mean, sigma;            // the colour (linear BGR) and its standard deviation
  std::array<bool, 3> observed;  // B, G, R seen on their own mosaic sites
  int samples;
  bool phase_averaged;
};

// The colour of yarn y from its samples: the mean cross-section integral when phase-averaged
// (with enough of them), else the mean of the best covered keep_fraction of the samples with the
// red or blue channel ignored whose mosaic sites the thread does not cross; `unseen` receives
// the names of those (" blue", " red").
MeasuredYarn MeanYarnColour(const KnotView& view, int y, YarnSamples s,
                            const LocalBackground& background, std::string* unseen) {
  const IdentifyOptions& options = view.options;
  auto& samples = s.samples;
  std::sort(samples.begin(), samples.end(),
            [](const auto& a, const auto& b) { return a.first > b.first; });
  const size_t keep =
      std::max<size_t>(std::min<size_t>(samples.size(), options.min_samples),
                       static_cast<size_t>(std::ceil(options.keep_fraction * samples.size())));
  Colour mean(0, 0, 0);
  for (size_t i = 0; i < keep; ++i) mean += samples[i].second;
  mean *= 1.0f / static_cast<float>(keep);
  // Neighbouring samples share pixels (bilinear sampling, demosaicing): count half of them
  // as independent.
  const Colour& pixel_sigma = background.pixel_sigma;
  Colour mean_sigma = pixel_sigma * (1.0f / std::sqrt(0.5f * static_cast<float>(keep)));
  std::array<bool, 3> observed{true, true, true};
  if (s.phase_averaged && static_cast<int>(s.integrals.size()) >= options.min_samples) {
    Colour sum(0, 0, 0);
    for (const Colour& c : s.integrals) sum += c;
    mean = background.colour + sum * (1.0f / static_cast<float>(s.integrals.size()));
    mean_sigma = pixel_sigma * std::sqrt(5.0f / (0.5f * static_cast<float>(s.integrals.size())));
  } else if (options.bayer != BayerPattern::kNone) {
    for (int c : {0, 2}) {
      if (s.sites[c] < options.min_channel_sites) {
        observed[c] = false;
        *unseen += c == 0 ? " blue" : " red";
      }
    }
  }
  return {y, mean, mean_sigma, observed, static_cast<int>(samples.size()), s.phase_averaged};
}

// Samples yarn y and measures its colour. Appends its reading to result->yarns (a placeholder
// that classification replaces when the colour was measured) and what it has to say to
// result->reasons. nullopt when the colour cannot be read: then every palette colour is
// plausible.
std::optional<MeasuredYarn> MeasureYarn(const KnotView& view, int y,
                                        const LocalBackground& background,
                                        KnotIdentification* result) {
  YarnSamples samples = SampleYarn(view, y, background.colour);
  if (const std::string why = WhyColourUnread(view, y, samples); !why.empty()) {
    YarnReading reading;
    reading.samples = static_cast<int>(samples.samples.size());
    reading.plausible = AllPaletteIndices(view.codebook.palette.size());
    result->reasons.push_back(why);
    result->yarns.push_back(reading);
    return std::nullopt;
  }
  std::string unseen;
  const MeasuredYarn measured = MeanYarnColour(view, y, std::move(samples), background, &unseen);
  if (!unseen.empty()) {
    result->reasons.push_back("yarn " + std::to_string(y) + ": runs along the mosaic, no" + unseen +
                              " sites under it: channel ignored");
  }
  result->yarns.push_back(YarnReading{});
  return measured;
}

// A measured yarn classified against the palette with its coverage (width) in [alpha_lo,
// alpha_hi].
YarnReading ClassifyMeasured(const KnotView& view, const MeasuredYarn& m, const Colour& background,
                             double alpha_lo, double alpha_hi) {
  IdentifyOptions o = view.options;
  o.alpha_min = alpha_lo;
  o.alpha_max = alpha_hi;
  YarnReading r =
      ClassifyYarnColour(m.mean, background, view.codebook.palette, o, m.observed, m.sigma);
  r.samples = m.samples;
  return r;
}

// Classification. The threads of one net have one diameter and meet at one depth, so their
// image widths agree: the coverage (width) fitted to each phase-averaged yarn must lie within
// width_tolerance of the median width of the yarns read with certainty. A colour that fits
// only as a much thinner or wider thread (a dim yellow for an orange under a colour cast) is
// thereby rejected. Replaces the measured yarns' readings in result->yarns.
void ClassifyMeasuredYarns(const KnotView& view, const std::vector<MeasuredYarn>& measured,
                           KnotIdentification* result) {
  const IdentifyOptions& options = view.options;
  const Colour& background = result->background;
  for (const MeasuredYarn& m : measured) {
    result->yarns[m.y] =
        ClassifyMeasured(view, m, background, options.alpha_min, options.alpha_max);
  }
  // The widths of the phase-averaged yarns read with certainty.
  std::vector<double> widths;
  for (const MeasuredYarn& m : measured) {
    const YarnReading& r = result->yarns[m.y];
    if (m.phase_averaged && r.plausible.size() == 1 && r.best_delta_e <= options.max_delta_e) {
      widths.push_back(r.alpha);
    }
  }
  // Two or more: every phase-averaged yarn again, its width near their median.
  if (widths.size() >= 2 && options.width_tolerance > 0) {
    std::sort(widths.begin(), widths.end());
    const double width = widths[widths.size() / 2];
    for (const MeasuredYarn& m : measured) {
      if (!m.phase_averaged) continue;
      result->yarns[m.y] = ClassifyMeasured(
          view, m, background, std::max(options.alpha_min, width / options.width_tolerance),
          std::min(options.alpha_max, width * options.width_tolerance));
    }
    char text[120];
    std::snprintf(text, sizeof(text), "thread width %.2f px (x/ %.2f allowed)", width,
                  options.width_tolerance);
    result->reasons.push_back(text);
  }
}

// One line on a classified yarn: unknown, uncertain (its plausible colours) or its colour.
std::string DescribeReading(const KnotView& view, int y, const YarnReading& reading) {
  const std::vector<PaletteColour>& palette = view.codebook.palette;
  const std::string name = palette[reading.best].name;
  char text[200];
  if (reading.best_delta_e > view.options.max_delta_e) {
    std::snprintf(text, sizeof(text), "yarn %d: unknown colour (nearest %s at dE00 %.1f > %.1f)", y,
                  name.c_str(), reading.best_delta_e, view.options.max_delta_e);
  } else if (reading.plausible.size() > 1) {
    std::string others;
    for (int c : reading.plausible) others += (others.empty() ? "" : "/") + palette[c].name;
    std::snprintf(text, sizeof(text), "yarn %d: uncertain colour %s (dE00 %.1f vs %.1f)", y,
                  others.c_str(), reading.best_delta_e, reading.second_delta_e);
  } else {
    std::snprintf(text, sizeof(text), "yarn %d: %s (dE00 %.1f, next %.1f, width %.2f)", y,
                  name.c_str(), reading.best_delta_e, reading.second_delta_e, reading.alpha);
  }
  return text;
}

// The codebook search: the candidate knots (options.candidate_knots, else all) that fit some
// plausible reading of the yarns.
std::vector<int> KnotsFittingSomeReading(const KnotView& view,
                                         const std::vector<std::vector<int>>& plausible) {
  std::vector<int> considered = view.options.candidate_knots;
  if (considered.empty()) {
    for (size_t k = 0; k < view.codebook.knots.size(); ++k) {
      considered.push_back(static_cast<int>(k));
    }
  }
  std::vector<int> fitting;
  for (int k : considered) {
    if (view.codebook.FitsSomeReading(k, plausible)) fitting.push_back(k);
  }
  return fitting;
}

// One knot fits. Identified only when some yarn was read with certainty and the best reading
// of every read yarn (the unread ones free) is its code; else unknown. `all_clear`: every yarn
// has one plausible colour.
void ConfirmTheOneKnot(const KnotView& view, bool all_clear, KnotIdentification* result) {
  const int n = view.yarns();
  const int knot = result->knots.front();
  const std::string name = KnotName(view.codebook.knots[knot]);
  std::vector<std::vector<int>> best_reading(n);
  int certain = 0;
  for (int y = 0; y < n; ++y) {
    const YarnReading& r = result->yarns[y];
    const bool read = r.best >= 0 && r.best_delta_e <= view.options.max_delta_e;
    best_reading[y] = read ? std::vector<int>{r.best} : r.plausible;
    if (read && r.plausible.size() == 1) ++certain;
  }
  if (certain == 0) {
    result->status = IdentifyStatus::kUnknown;
    result->knots.clear();
    result->reasons.push_back("no yarn colour read with certainty");
    return;
  }
  if (!view.codebook.FitsSomeReading(knot, best_reading)) {
    result->status = IdentifyStatus::kUnknown;
    result->knots.clear();
    result->reasons.push_back("only a second-choice reading fits knot " + name);
    return;
  }
  // The confidence: the least of the clear yarns', halved and scaled by their share when some
  // yarn is not clear.
  result->status = IdentifyStatus::kIdentified;
  double confidence = 1.0;
  int clear = 0;
  for (const YarnReading& r : result->yarns) {
    if (r.plausible.size() == 1) confidence = std::min(confidence, r.confidence), ++clear;
  }
  result->confidence = confidence * (all_clear ? 1.0 : 0.5 * clear / n);
  result->reasons.push_back("knot " + name +
                            (all_clear ? "" : " (every plausible reading gives it)"));
}

// The decision from the yarns' readings: unknown when no knot fits, ambiguous when several do,
// else identified when the one knot is confirmed; the reason appended.
void Decide(const KnotView& view, KnotIdentification* result) {
  bool all_clear = true;
  std::vector<std::vector<int>> plausible(view.yarns());
  for (int y = 0; y < view.yarns(); ++y) {
    all_clear = all_clear && result->yarns[y].plausible.size() == 1;
    plausible[y] = result->yarns[y].plausible;
  }
  result->knots = KnotsFittingSomeReading(view, plausible);
  if (result->knots.empty()) {
    result->status = IdentifyStatus::kUnknown;
    result->reasons.push_back("no knot of the codebook has these colours");
    return;
  }
  if (result->knots.size() > 1) {
    result->status = IdentifyStatus::kAmbiguous;
    std::string list;
    for (int k : result->knots) {
      // (Appended in two steps: GCC 12 warns falsely on (... ? "" : " ") + KnotName(...) here.)
      if (!list.empty()) list += ' ';
      list += KnotName(view.codebook.knots[k]);
    }
    result->reasons.push_back(std::to_string(result->knots.size()) + " knots fit: " + list);
    return;
  }
  ConfirmTheOneKnot(view, all_clear, result);
}

}  // namespace

KnotIdentification IdentifyKnot(const cv::Mat& bgr8, const Eigen::Vector2d& knot_px,
                                const std::vector<Eigen::Vector2d>& yarn_directions,
                                const IdentifyOptions& options, const KnotCodebook& codebook) {
  const std::vector<Eigen::Vector2d> dirs =
      CheckedUnitDirections(bgr8, yarn_directions, options, codebook);
  KnotIdentification result;
  const LinearSampler sampler(bgr8, options.image_is_linear);
  const KnotView view{sampler, knot_px, dirs, options, codebook};

  // The yarns must stay inside the frame.
  const double margin = options.outer_radius_px + options.search_half_width_px + 2;
  if (!(knot_px.x() >= margin && knot_px.y() >= margin && knot_px.x() < bgr8.cols - 1 - margin &&
        knot_px.y() < bgr8.rows - 1 - margin)) {
    result.reasons.push_back("knot within " + std::to_string(margin) + " px of the border");
    return result;
  }

  // The local background and the pixel noise on it.
  const std::optional<LocalBackground> background = EstimateLocalBackground(view);
  if (!background) {
    result.reasons.push_back("no background visible between the yarns");
    return result;
  }
  result.background = background->colour;

  // Each yarn: the most contrasted point of each cross-section, the best covered of them
  // averaged.
  std::vector<MeasuredYarn> measured;
  for (int y = 0; y < view.yarns(); ++y) {
    if (std::optional<MeasuredYarn> m = MeasureYarn(view, y, *background, &result)) {
      measured.push_back(*m);
    }
  }

  // Their colours classified against the palette (the widths made to agree), each explained.
  ClassifyMeasuredYarns(view, measured, &result);
  for (const MeasuredYarn& m : measured) {
    result.reasons.push_back(DescribeReading(view, m.y, result.yarns[m.y]));
  }

  // The knots that fit some plausible reading, and the decision.
  Decide(view, &result);
  return result;
}

}  // namespace netlab::recon
