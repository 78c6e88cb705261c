#include "libreconstruct/coloring/color_identify.h"

#include <algorithm>
#include <cstdio>
#include <cmath>
#include <fstream>
#include <limits>
#include <numbers>
#include <random>
#include <set>
#include <sstream>
#include <stdexcept>

namespace netlab::recon {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kDegToRad = std::numbers::pi / 180.0;

double Clamp01(double v) { return std::clamp(v, 0.0, 1.0); }

// CIE 1976 f(t) and its inverse (CIE 15:2004, eq. 8.3 / 8.4), delta = 6/29.
double LabF(double t) {
  constexpr double kDelta = 6.0 / 29.0;
  return t > kDelta * kDelta * kDelta ? std::cbrt(t) : t / (3 * kDelta * kDelta) + 4.0 / 29.0;
}
double LabFInverse(double f) {
  constexpr double kDelta = 6.0 / 29.0;
  return f > kDelta ? f * f * f : 3 * kDelta * kDelta * (f - 4.0 / 29.0);
}

// Hue angle in degrees in [0, 360); 0 for the achromatic point (Sharma et al., eq. 4).
double HueDegrees(double b, double a_prime) {
  if (a_prime == 0.0 && b == 0.0) return 0.0;
  double h = std::atan2(b, a_prime) / kDegToRad;
  if (h < 0) h += 360.0;
  return h;
}

std::string Trim(const std::string& s) {
  const auto begin = s.find_first_not_of(" \t\r\n\"'");
  if (begin == std::string::npos) return "";
  const auto end = s.find_last_not_of(" \t\r\n\"'");
  return s.substr(begin, end - begin + 1);
}

bool ParseNumber(const std::string& text, double* value) {
  if (text.empty()) return false;
  char* end = nullptr;
  *value = std::strtod(text.c_str(), &end);
  return end == text.c_str() + text.size() && std::isfinite(*value);
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// Colour science.

double SrgbToLinear(double encoded) {
  return encoded <= 0.04045 ? encoded / 12.92 : std::pow((encoded + 0.055) / 1.055, 2.4);
}

double LinearToSrgb(double linear) {
  return linear <= 0.0031308 ? 12.92 * linear : 1.055 * std::pow(linear, 1.0 / 2.4) - 0.055;
}

Colour SrgbToLinearBgr(const std::array<double, 3>& srgb_rgb) {
  return Colour(static_cast<float>(SrgbToLinear(srgb_rgb[2] / 255.0)),
                static_cast<float>(SrgbToLinear(srgb_rgb[1] / 255.0)),
                static_cast<float>(SrgbToLinear(srgb_rgb[0] / 255.0)));
}

std::array<double, 3> LinearBgrToSrgb(const Colour& bgr) {
  std::array<double, 3> rgb;
  for (int c = 0; c < 3; ++c) {
    rgb[c] = std::round(255.0 * Clamp01(LinearToSrgb(Clamp01(bgr[2 - c]))));
  }
  return rgb;
}

Eigen::Vector3d LinearBgrToXyz(const Colour& bgr) {
  // IEC 61966-2-1 primaries, D65 white.
  const double r = bgr[2], g = bgr[1], b = bgr[0];
  return {0.4124564 * r + 0.3575761 * g + 0.1804375 * b,
          0.2126729 * r + 0.7151522 * g + 0.0721750 * b,
          0.0193339 * r + 0.1191920 * g + 0.9503041 * b};
}

Eigen::Vector3d D65White() { return LinearBgrToXyz(Colour(1, 1, 1)); }

Lab XyzToLab(const Eigen::Vector3d& xyz, const Eigen::Vector3d& white_xyz) {
  const double fx = LabF(xyz.x() / white_xyz.x());
  const double fy = LabF(xyz.y() / white_xyz.y());
  const double fz = LabF(xyz.z() / white_xyz.z());
  return {116.0 * fy - 16.0, 500.0 * (fx - fy), 200.0 * (fy - fz)};
}

Eigen::Vector3d LabToXyz(const Lab& lab, const Eigen::Vector3d& white_xyz) {
  const double fy = (lab.l + 16.0) / 116.0;
  const double fx = fy + lab.a / 500.0;
  const double fz = fy - lab.b / 200.0;
  return {white_xyz.x() * LabFInverse(fx), white_xyz.y() * LabFInverse(fy),
          white_xyz.z() * LabFInverse(fz)};
}

Lab LinearBgrToLab(const Colour& bgr) { return XyzToLab(LinearBgrToXyz(bgr)); }

double CieDe2000(const Lab& x, const Lab& y, double k_l, double k_c, double k_h) {
  // Eq. 2-5: C*, G, a', C', h'.
  const double c1 = std::hypot(x.a, x.b), c2 = std::hypot(y.a, y.b);
  const double c_mean = 0.5 * (c1 + c2);
  const double c_mean7 = std::pow(c_mean, 7.0);
  constexpr double k25_7 = 6103515625.0;  // 25^7
  const double g = 0.5 * (1.0 - std::sqrt(c_mean7 / (c_mean7 + k25_7)));
  const double a1p = (1.0 + g) * x.a, a2p = (1.0 + g) * y.a;
  const double c1p = std::hypot(a1p, x.b), c2p = std::hypot(a2p, y.b);
  const double h1p = HueDegrees(x.b, a1p), h2p = HueDegrees(y.b, a2p);

  // Eq. 8-11: differences; the hue difference wraps into [-180, 180], 0 for an achromatic one.
  const double dl = y.l - x.l;
  const double dc = c2p - c1p;
  double dh = 0.0;
  if (c1p * c2p != 0.0) {
    dh = h2p - h1p;
    if (dh > 180.0) dh -= 360.0;
    if (dh < -180.0) dh += 360.0;
  }
  const double dhh = 2.0 * std::sqrt(c1p * c2p) * std::sin(0.5 * dh * kDegToRad);

  // Eq. 12-22: means and weighting functions.
  const double l_mean = 0.5 * (x.l + y.l);
  const double cp_mean = 0.5 * (c1p + c2p);
  double h_mean = h1p + h2p;
  if (c1p * c2p != 0.0) {
    if (std::abs(h1p - h2p) <= 180.0) {
      h_mean = 0.5 * (h1p + h2p);
    } else if (h1p + h2p < 360.0) {
      h_mean = 0.5 * (h1p + h2p + 360.0);
    } else {
      h_mean = 0.5 * (h1p + h2p - 360.0);
    }
  }
  const double t = 1.0 - 0.17 * std::cos((h_mean - 30.0) * kDegToRad) +
                   0.24 * std::cos(2.0 * h_mean * kDegToRad) +
                   0.32 * std::cos((3.0 * h_mean + 6.0) * kDegToRad) -
                   0.20 * std::cos((4.0 * h_mean - 63.0) * kDegToRad);
  const double d_theta = 30.0 * std::exp(-std::pow((h_mean - 275.0) / 25.0, 2.0));
  const double cp_mean7 = std::pow(cp_mean, 7.0);
  const double r_c = 2.0 * std::sqrt(cp_mean7 / (cp_mean7 + k25_7));
  const double l50 = (l_mean - 50.0) * (l_mean - 50.0);
  const double s_l = 1.0 + 0.015 * l50 / std::sqrt(20.0 + l50);
  const double s_c = 1.0 + 0.045 * cp_mean;
  const double s_h = 1.0 + 0.015 * cp_mean * t;
  const double r_t = -std::sin(2.0 * d_theta * kDegToRad) * r_c;
  const double tl = dl / (k_l * s_l), tc = dc / (k_c * s_c), th = dhh / (k_h * s_h);
  return std::sqrt(std::max(0.0, tl * tl + tc * tc + th * th + r_t * tc * th));
}

// ---------------------------------------------------------------------------------------------
// The physical palette.

Colour Lighting::Seen(const std::array<double, 3>& srgb_rgb) const {
  const Colour linear = SrgbToLinearBgr(srgb_rgb);
  Colour seen;
  for (int c = 0; c < 3; ++c) {
    seen[c] = static_cast<float>(Clamp01(exposure * gains_bgr[c] * linear[c]));
  }
  return seen;
}

Lab Lighting::SeenLab(const std::array<double, 3>& srgb_rgb) const {
  return XyzToLab(LinearBgrToXyz(Seen(srgb_rgb)), white_xyz);
}

bool Lighting::IsValid(std::string* error) const {
  auto fail = [&](const std::string& why) {
    if (error) *error = why;
    return false;
  };
  for (double g : gains_bgr) {
    if (!(g > 0) || !std::isfinite(g)) return fail("Lighting: gains_bgr must be finite and > 0");
  }
  if (!(exposure > 0) || !std::isfinite(exposure)) return fail("Lighting: exposure must be > 0");
  if (!(white_xyz.y() > 0) || !(white_xyz.x() > 0) || !(white_xyz.z() > 0)) {
    return fail("Lighting: white_xyz must be positive");
  }
  return true;
}

namespace {

// Pairwise and background CIEDE2000 of the candidates as seen.
struct PaletteDistances {
  int n = 0;
  std::vector<double> pair;  // n x n
  std::vector<double> background;  // n (inf without background)
  double D(int i, int j) const { return pair[static_cast<size_t>(i) * n + j]; }
};

PaletteDistances ComputeDistances(const std::vector<Candidate>& candidates,
                                  const Lighting& lighting) {
  PaletteDistances d;
  d.n = static_cast<int>(candidates.size());
  std::vector<Lab> lab(d.n);
  for (int i = 0; i < d.n; ++i) lab[i] = lighting.SeenLab(candidates[i].srgb);
  d.pair.assign(static_cast<size_t>(d.n) * d.n, 0.0);
  for (int i = 0; i < d.n; ++i) {
    for (int j = i + 1; j < d.n; ++j) {
      d.pair[static_cast<size_t>(i) * d.n + j] = d.pair[static_cast<size_t>(j) * d.n + i] =
          CieDe2000(lab[i], lab[j]);
    }
  }
  d.background.assign(d.n, kInf);
  if (lighting.background) {
    const Lab bg = XyzToLab(LinearBgrToXyz(*lighting.background), lighting.white_xyz);
    for (int i = 0; i < d.n; ++i) d.background[i] = CieDe2000(lab[i], bg);
  }
  return d;
}

double Objective(const PaletteDistances& d, const std::vector<int>& chosen) {
  double m = kInf;
  for (size_t a = 0; a < chosen.size(); ++a) {
    m = std::min(m, d.background[chosen[a]]);
    for (size_t b = a + 1; b < chosen.size(); ++b) m = std::min(m, d.D(chosen[a], chosen[b]));
  }
  return m;
}

// Greedy farthest-point selection, then single swaps while one raises the minimum.
std::vector<int> GreedySwap(const PaletteDistances& d, int k) {
  std::vector<int> chosen;
  std::vector<bool> in(d.n, false);
  // Seed: the candidate farthest from the background, or the first when there is none.
  int seed = 0;
  for (int i = 1; i < d.n; ++i) {
    if (d.background[i] > d.background[seed]) seed = i;
  }
  chosen.push_back(seed);
  in[seed] = true;
  while (static_cast<int>(chosen.size()) < k) {
    int best = -1;
    double best_value = -1;
    for (int i = 0; i < d.n; ++i) {
      if (in[i]) continue;
      double m = d.background[i];
      for (int j : chosen) m = std::min(m, d.D(i, j));
      if (m > best_value) best_value = m, best = i;
    }
    chosen.push_back(best);
    in[best] = true;
  }
  double value = Objective(d, chosen);
  for (bool improved = true; improved;) {
    improved = false;
    for (int slot = 0; slot < k && !improved; ++slot) {
      for (int i = 0; i < d.n && !improved; ++i) {
        if (in[i]) continue;
        std::vector<int> trial = chosen;
        trial[slot] = i;
        const double v = Objective(d, trial);
        if (v > value + 1e-12) {
          in[chosen[slot]] = false;
          in[i] = true;
          chosen = trial;
          value = v;
          improved = true;
        }
      }
    }
  }
  std::sort(chosen.begin(), chosen.end());
  return chosen;
}

// Depth-first over subsets in index order; a branch ends as soon as its running minimum cannot
// beat the best complete choice (the minimum only falls as candidates are added).
void BranchAndBound(const PaletteDistances& d, int k, int start, std::vector<int>* chosen,
                    double running_min, double* best_value, std::vector<int>* best) {
  if (static_cast<int>(chosen->size()) == k) {
    if (running_min > *best_value) {
      *best_value = running_min;
      *best = *chosen;
    }
    return;
  }
  const int missing = k - static_cast<int>(chosen->size());
  for (int i = start; i + missing <= d.n; ++i) {
    double m = std::min(running_min, d.background[i]);
    for (int j : *chosen) m = std::min(m, d.D(i, j));
    if (!(m > *best_value)) continue;
    chosen->push_back(i);
    BranchAndBound(d, k, i + 1, chosen, m, best_value, best);
    chosen->pop_back();
  }
}

}  // namespace

double PaletteMinDeltaE(const std::vector<Candidate>& candidates, const std::vector<int>& chosen,
                        const Lighting& lighting) {
  return Objective(ComputeDistances(candidates, lighting), chosen);
}

std::vector<int> ChoosePalette(const std::vector<Candidate>& candidates, int k,
                               const Lighting& lighting, double* min_delta_e) {
  std::string error;
  if (!lighting.IsValid(&error)) throw std::invalid_argument("ChoosePalette: " + error);
  if (k < 1 || k > static_cast<int>(candidates.size())) {
    throw std::invalid_argument("ChoosePalette: k = " + std::to_string(k) + " with " +
                                std::to_string(candidates.size()) + " candidates");
  }
  const PaletteDistances d = ComputeDistances(candidates, lighting);
  std::vector<int> best = GreedySwap(d, k);
  double best_value = Objective(d, best);
  if (d.n <= kExactPaletteCandidates) {
    // The local optimum is the incumbent: only strictly better subsets replace it.
    std::vector<int> chosen;
    BranchAndBound(d, k, 0, &chosen, kInf, &best_value, &best);
  }
  std::sort(best.begin(), best.end());
  if (min_delta_e) *min_delta_e = best_value;
  return best;
}

std::vector<Candidate> LoadCandidates(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("LoadCandidates: cannot read " + path);
  std::vector<Candidate> out;
  std::set<std::string> names;
  std::string line;
  for (int number = 1; std::getline(in, line); ++number) {
    auto fail = [&](const std::string& why) {
      throw std::runtime_error(path + ":" + std::to_string(number) + ": " + why + " in \"" +
                               Trim(line) + "\"");
    };
    std::string text = line.substr(0, line.find('#'));
    text = Trim(text);
    if (text.empty()) continue;
    if (text[0] == '-') text = Trim(text.substr(1));
    // A YAML key introducing the list ("candidates:") carries no colour.
    if (text.back() == ':' && text.find(',') == std::string::npos) continue;
    for (char& c : text) {
      if (c == '[' || c == ']' || c == '{' || c == '}') c = ' ';
    }
    std::vector<std::string> fields;
    std::stringstream stream(text);
    for (std::string field; std::getline(stream, field, ',');) fields.push_back(Trim(field));
    std::string name;
    std::array<std::string, 3> values;
    if (text.find(':') != std::string::npos) {
      // YAML flow mapping: name: x, r: .., g: .., b: ..
      std::array<bool, 4> seen{false, false, false, false};
      for (const std::string& field : fields) {
        const auto colon = field.find(':');
        if (colon == std::string::npos) fail("expected key: value");
        const std::string key = Trim(field.substr(0, colon));
        const std::string value = Trim(field.substr(colon + 1));
        const int slot = key == "name" ? 0 : key == "r" ? 1 : key == "g" ? 2 : key == "b" ? 3 : -1;
        if (slot < 0) fail("unknown key '" + key + "' (name, r, g, b)");
        seen[slot] = true;
        if (slot == 0) name = value;
        else values[slot - 1] = value;
      }
      if (!(seen[0] && seen[1] && seen[2] && seen[3])) fail("expected keys name, r, g, b");
    } else {
      if (fields.size() != 4) fail("expected 4 fields 'name, r, g, b'");
      name = fields[0];
      values = {fields[1], fields[2], fields[3]};
      // A CSV header.
      if (out.empty() && values[0] == "r" && values[1] == "g" && values[2] == "b") continue;
    }
    if (name.empty()) fail("empty name");
    Candidate candidate;
    candidate.name = name;
    for (int c = 0; c < 3; ++c) {
      double v = 0;
      if (!ParseNumber(values[c], &v)) fail("'" + values[c] + "' is not a number");
      if (v < 0 || v > 255) fail("value " + values[c] + " outside 0..255");
      candidate.srgb[c] = v;
    }
    if (!names.insert(name).second) fail("duplicate name '" + name + "'");
    out.push_back(candidate);
  }
  if (out.empty()) throw std::runtime_error("LoadCandidates: no candidates in " + path);
  return out;
}

std::vector<Candidate> DefaultYarnCandidates() {
  return {
      {"white", {240, 240, 235}},      {"black", {25, 25, 28}},
      {"red", {200, 30, 40}},          {"dark red", {120, 20, 35}},
      {"orange", {240, 120, 20}},      {"yellow", {250, 210, 30}},
      {"lime", {150, 200, 40}},        {"green", {20, 140, 60}},
      {"dark green", {20, 75, 40}},    {"turquoise", {30, 180, 180}},
      {"light blue", {110, 170, 230}}, {"royal blue", {30, 60, 170}},
      {"navy", {20, 30, 80}},          {"purple", {110, 40, 140}},
      {"pink", {240, 120, 170}},       {"brown", {110, 70, 35}},
  };
}

// ---------------------------------------------------------------------------------------------
// Identification.

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
                              std::to_string(knot.row) + ", col " + std::to_string(knot.col) +
                              ")";
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


}  // namespace

YarnReading ClassifyYarnColour(const Colour& measured, const Colour& background,
                               const std::vector<PaletteColour>& palette,
                               const IdentifyOptions& options,
                               const std::array<bool, 3>& observed,
                               const Colour& measured_sigma) {
  YarnReading r;
  // The ΔE00 that noise_sigmas standard deviations of the measurement make, per channel.
  {
    const Lab lab = LinearBgrToLab(measured);
    for (int c = 0; c < 3; ++c) {
      for (float sign : {-1.0f, 1.0f}) {
        Colour moved = measured;
        moved[c] = std::max(0.0f, moved[c] + sign * static_cast<float>(options.noise_sigmas) *
                                                 measured_sigma[c]);
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
    for (size_t c = 0; c < palette.size(); ++c) r.plausible.push_back(static_cast<int>(c));
    r.confidence = 0.0;
    return r;
  }
  const double gap = std::max({options.ambiguity_margin, options.ambiguity_ratio * r.best_delta_e,
                               r.noise_delta_e});
  for (size_t c = 0; c < palette.size(); ++c) {
    if (score[c] <= r.best_delta_e + gap) r.plausible.push_back(static_cast<int>(c));
  }
  if (r.plausible.size() == 1) {
    const double excess = std::isfinite(r.second_delta_e)
                              ? (r.second_delta_e - r.best_delta_e) / (2.0 * gap)
                              : 1.0;
    r.confidence = std::clamp(excess, 0.5, 1.0) *
                   (1.0 - 0.5 * r.best_delta_e / options.max_delta_e);
  }
  return r;
}

KnotIdentification IdentifyKnot(const cv::Mat& bgr8, const Eigen::Vector2d& knot_px,
                                const std::vector<Eigen::Vector2d>& yarn_directions,
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

  KnotIdentification result;
  const LinearSampler sampler(bgr8, options.image_is_linear);
  const double margin = options.outer_radius_px + options.search_half_width_px + 2;
  if (!(knot_px.x() >= margin && knot_px.y() >= margin && knot_px.x() < bgr8.cols - 1 - margin &&
        knot_px.y() < bgr8.rows - 1 - margin)) {
    result.reasons.push_back("knot within " + std::to_string(margin) + " px of the border");
    return result;
  }

  Colour pixel_sigma(0, 0, 0);
  // Local background: the median of a ring around the knot away from every yarn (>= 25 deg).
  {
    std::vector<float> channel[3];
    const double cos_limit = std::cos(25.0 * kDegToRad);
    for (double radius = options.inner_radius_px + 2; radius <= options.outer_radius_px;
         radius += 2) {
      for (int a = 0; a < 72; ++a) {
        const Eigen::Vector2d u(std::cos(a * 5 * kDegToRad), std::sin(a * 5 * kDegToRad));
        bool clear = true;
        for (const Eigen::Vector2d& d : dirs) clear = clear && u.dot(d) < cos_limit;
        Colour c;
        // At pixel centres: bilinear interpolation would smooth the noise measured here.
        const Eigen::Vector2d at = (knot_px + radius * u).array().round().matrix();
        if (!clear || !sampler.At(at, &c)) continue;
        for (int k = 0; k < 3; ++k) channel[k].push_back(c[k]);
      }
    }
    if (channel[0].empty()) {
      result.reasons.push_back("no background visible between the yarns");
      return result;
    }
    for (int k = 0; k < 3; ++k) {
      auto mid = channel[k].begin() + channel[k].size() / 2;
      std::nth_element(channel[k].begin(), mid, channel[k].end());
      result.background[k] = *mid;
      // Pixel noise: 1.4826 x the median absolute deviation (a Gaussian's sigma).
      std::vector<float> deviation;
      for (float v : channel[k]) deviation.push_back(std::abs(v - result.background[k]));
      auto dmid = deviation.begin() + deviation.size() / 2;
      std::nth_element(deviation.begin(), dmid, deviation.end());
      pixel_sigma[k] = 1.4826f * *dmid;
    }
  }

  // Each yarn: the most contrasted point of each cross-section, the best covered of them
  // averaged, classified against the palette.
  std::vector<std::vector<int>> plausible(n);
  struct PendingYarn {
    int y;
    Colour mean, sigma;
    std::array<bool, 3> observed;
    int samples;
    bool phase_averaged;
  };
  std::vector<PendingYarn> pending;
  bool all_clear = true;
  for (int y = 0; y < n; ++y) {
    const Eigen::Vector2d d = dirs[y], across(-d.y(), d.x());
    std::vector<std::pair<double, Colour>> samples;
    std::array<int, 3> sites{0, 0, 0};  // mosaic sites of each colour under the centreline
    std::vector<Colour> integrals;
    // A thread that crosses at least one mosaic period (2 px) of rows and of columns along the
    // segment has seen every colour site at every phase: the mean cross-section integral is an
    // unbiased colour. Else (near an image axis) the best covered samples, with the channels
    // whose sites it never crosses ignored.
    const double travel = (options.outer_radius_px - options.inner_radius_px) *
                          std::min(std::abs(d.x()), std::abs(d.y()));
    const bool phase_averaged =
        options.bayer == BayerPattern::kNone || travel >= options.min_phase_travel_px;
    for (double r = options.inner_radius_px; r <= options.outer_radius_px + 1e-9;
         r += options.step_px) {
      double best_contrast = -1;
      Colour best_colour;
      Eigen::Vector2d best_p;
      for (double t = -options.search_half_width_px; t <= options.search_half_width_px + 1e-9;
           t += 0.5) {
        const Eigen::Vector2d p = knot_px + r * d + t * across;
        // Not nearer another yarn than 2 px (thread width and the bilinear footprint).
        bool own = true;
        for (int o = 0; o < n; ++o) {
          if (o != y && RayDistance(p, knot_px, dirs[o]) < 2.0) own = false;
        }
        Colour c;
        if (!own || !sampler.At(p, &c)) continue;
        const double contrast = Contrast(c, result.background);
        if (contrast > best_contrast) best_contrast = contrast, best_colour = c, best_p = p;
      }
      if (best_contrast >= options.min_contrast) {
        samples.emplace_back(best_contrast, best_colour);
        // The cross-section integral around the thread's centre: sum of (pixel - background)
        // over 5 px across, i.e. width x (yarn - background) for a thread narrower than that.
        Colour integral(0, 0, 0);
        bool inside = true;
        for (int t = -2; t <= 2 && inside; ++t) {
          Colour c;
          inside = sampler.At(best_p + t * across, &c);
          integral += c - result.background;
        }
        if (inside) integrals.push_back(integral);
        if (options.bayer != BayerPattern::kNone) {
          const int site = BayerColor(options.bayer, static_cast<int>(std::lround(best_p.y())),
                                      static_cast<int>(std::lround(best_p.x())));
          if (site >= 0) ++sites[site];
        }
      }
    }
    YarnReading reading;
    if (!phase_averaged && !options.read_along_mosaic) {
      reading.samples = static_cast<int>(samples.size());
      for (size_t c = 0; c < codebook.palette.size(); ++c) {
        reading.plausible.push_back(static_cast<int>(c));
      }
      char text[200];
      std::snprintf(text, sizeof(text),
                    "yarn %d: runs along the pixel rows or columns (%.1f px across them over the "
                    "segment < %.1f): the mosaic does not see all its colours, colour unknown",
                    y, travel, options.min_phase_travel_px);
      result.reasons.push_back(text);
    } else if (static_cast<int>(samples.size()) < options.min_samples) {
      reading.samples = static_cast<int>(samples.size());
      for (size_t c = 0; c < codebook.palette.size(); ++c) {
        reading.plausible.push_back(static_cast<int>(c));
      }
      result.reasons.push_back("yarn " + std::to_string(y) + ": only " +
                               std::to_string(samples.size()) + " thread samples (need " +
                               std::to_string(options.min_samples) + "): colour unknown");
    } else {
      std::sort(samples.begin(), samples.end(),
                [](const auto& a, const auto& b) { return a.first > b.first; });
      const size_t keep = std::max<size_t>(
          std::min<size_t>(samples.size(), options.min_samples),
          static_cast<size_t>(std::ceil(options.keep_fraction * samples.size())));
      Colour mean(0, 0, 0);
      for (size_t i = 0; i < keep; ++i) mean += samples[i].second;
      mean *= 1.0f / static_cast<float>(keep);
      // Neighbouring samples share pixels (bilinear sampling, demosaicing): count half of them
      // as independent.
      Colour mean_sigma = pixel_sigma * (1.0f / std::sqrt(0.5f * static_cast<float>(keep)));
      std::array<bool, 3> observed{true, true, true};
      std::string unseen;
      if (phase_averaged && static_cast<int>(integrals.size()) >= options.min_samples) {
        Colour sum(0, 0, 0);
        for (const Colour& c : integrals) sum += c;
        mean = result.background + sum * (1.0f / static_cast<float>(integrals.size()));
        mean_sigma = pixel_sigma * std::sqrt(5.0f / (0.5f * static_cast<float>(integrals.size())));
      } else if (options.bayer != BayerPattern::kNone) {
        for (int c : {0, 2}) {
          if (sites[c] < options.min_channel_sites) {
            observed[c] = false;
            unseen += c == 0 ? " blue" : " red";
          }
        }
      }
      pending.push_back({y, mean, mean_sigma, observed, static_cast<int>(samples.size()),
                         phase_averaged});
      if (!unseen.empty()) {
        result.reasons.push_back("yarn " + std::to_string(y) + ": runs along the mosaic, no" +
                                 unseen + " sites under it: channel ignored");
      }
    }
    result.yarns.push_back(reading);
  }

  // Classification. The threads of one net have one diameter and meet at one depth, so their
  // image widths agree: the coverage (width) fitted to each phase-averaged yarn must lie within
  // width_tolerance of the median width of the yarns read with certainty. A colour that fits
  // only as a much thinner or wider thread (a dim yellow for an orange under a colour cast) is
  // thereby rejected.
  auto classify = [&](const PendingYarn& p, double alpha_lo, double alpha_hi) {
    IdentifyOptions o = options;
    o.alpha_min = alpha_lo;
    o.alpha_max = alpha_hi;
    YarnReading r =
        ClassifyYarnColour(p.mean, result.background, codebook.palette, o, p.observed, p.sigma);
    r.samples = p.samples;
    return r;
  };
  for (const PendingYarn& p : pending) {
    result.yarns[p.y] = classify(p, options.alpha_min, options.alpha_max);
  }
  std::vector<double> widths;
  for (const PendingYarn& p : pending) {
    const YarnReading& r = result.yarns[p.y];
    if (p.phase_averaged && r.plausible.size() == 1 && r.best_delta_e <= options.max_delta_e) {
      widths.push_back(r.alpha);
    }
  }
  if (widths.size() >= 2 && options.width_tolerance > 0) {
    std::sort(widths.begin(), widths.end());
    const double width = widths[widths.size() / 2];
    for (const PendingYarn& p : pending) {
      if (!p.phase_averaged) continue;
      result.yarns[p.y] = classify(p, std::max(options.alpha_min, width / options.width_tolerance),
                                   std::min(options.alpha_max, width * options.width_tolerance));
    }
    char text[120];
    std::snprintf(text, sizeof(text), "thread width %.2f px (x/ %.2f allowed)", width,
                  options.width_tolerance);
    result.reasons.push_back(text);
  }
  for (const PendingYarn& p : pending) {
    const YarnReading& reading = result.yarns[p.y];
    const std::string name = codebook.palette[reading.best].name;
    char text[200];
    if (reading.best_delta_e > options.max_delta_e) {
      std::snprintf(text, sizeof(text), "yarn %d: unknown colour (nearest %s at dE00 %.1f > %.1f)",
                    p.y, name.c_str(), reading.best_delta_e, options.max_delta_e);
    } else if (reading.plausible.size() > 1) {
      std::string others;
      for (int c : reading.plausible) {
        others += (others.empty() ? "" : "/") + codebook.palette[c].name;
      }
      std::snprintf(text, sizeof(text), "yarn %d: uncertain colour %s (dE00 %.1f vs %.1f)", p.y,
                    others.c_str(), reading.best_delta_e, reading.second_delta_e);
    } else {
      std::snprintf(text, sizeof(text), "yarn %d: %s (dE00 %.1f, next %.1f, width %.2f)", p.y,
                    name.c_str(), reading.best_delta_e, reading.second_delta_e, reading.alpha);
    }
    result.reasons.push_back(text);
  }
  for (int y = 0; y < n; ++y) {
    all_clear = all_clear && result.yarns[y].plausible.size() == 1;
    plausible[y] = result.yarns[y].plausible;
  }

  // Knots that fit some plausible reading, among the candidates.
  std::vector<int> considered = options.candidate_knots;
  if (considered.empty()) {
    for (size_t k = 0; k < codebook.knots.size(); ++k) considered.push_back(static_cast<int>(k));
  }
  for (int k : considered) {
    if (codebook.FitsSomeReading(k, plausible)) result.knots.push_back(k);
  }
  if (result.knots.empty()) {
    result.status = IdentifyStatus::kUnknown;
    result.reasons.push_back("no knot of the codebook has these colours");
    return result;
  }
  if (result.knots.size() > 1) {
    result.status = IdentifyStatus::kAmbiguous;
    std::string list;
    for (int k : result.knots) list += (list.empty() ? "" : " ") + KnotName(codebook.knots[k]);
    result.reasons.push_back(std::to_string(result.knots.size()) + " knots fit: " + list);
    return result;
  }
  // One knot fits. Identified only when some yarn was read with certainty and the best reading
  // of every read yarn (the unread ones free) is its code.
  const int knot = result.knots.front();
  std::vector<std::vector<int>> best_reading(n);
  int certain = 0;
  for (int y = 0; y < n; ++y) {
    const YarnReading& r = result.yarns[y];
    const bool read = r.best >= 0 && r.best_delta_e <= options.max_delta_e;
    best_reading[y] = read ? std::vector<int>{r.best} : r.plausible;
    if (read && r.plausible.size() == 1) ++certain;
  }
  if (certain == 0) {
    result.status = IdentifyStatus::kUnknown;
    result.knots.clear();
    result.reasons.push_back("no yarn colour read with certainty");
    return result;
  }
  if (!codebook.FitsSomeReading(knot, best_reading)) {
    result.status = IdentifyStatus::kUnknown;
    result.knots.clear();
    result.reasons.push_back("only a second-choice reading fits knot " +
                             KnotName(codebook.knots[knot]));
    return result;
  }
  result.status = IdentifyStatus::kIdentified;
  double confidence = 1.0;
  int clear = 0;
  for (const YarnReading& r : result.yarns) {
    if (r.plausible.size() == 1) confidence = std::min(confidence, r.confidence), ++clear;
  }
  result.confidence = confidence * (all_clear ? 1.0 : 0.5 * clear / n);
  result.reasons.push_back("knot " + KnotName(codebook.knots[knot]) +
                           (all_clear ? "" : " (every plausible reading gives it)"));
  return result;
}

}  // namespace netlab::recon
