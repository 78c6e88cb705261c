#include "libreconstruct/coloring/palette.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <set>
#include <sstream>
#include <stdexcept>

namespace netlab::recon {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

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

Colour Lighting::Seen(const std::array<double, 3>& srgb_rgb) const {
  const Colour linear = SrgbToLinearBgr(srgb_rgb);
  Colour seen;
  for (int c = 0; c < 3; ++c) {
    seen[c] = static_cast<float>(std::clamp(exposure * gains_bgr[c] * linear[c], 0.0, 1.0));
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
  std::vector<double> pair;        // n x n
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
        if (slot == 0)
          name = value;
        else
          values[slot - 1] = value;
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
      {"white", {240, 240, 235}},    {"black", {25, 25, 28}},         {"red", {200, 30, 40}},
      {"dark red", {120, 20, 35}},   {"orange", {240, 120, 20}},      {"yellow", {250, 210, 30}},
      {"lime", {150, 200, 40}},      {"green", {20, 140, 60}},        {"dark green", {20, 75, 40}},
      {"turquoise", {30, 180, 180}}, {"light blue", {110, 170, 230}}, {"royal blue", {30, 60, 170}},
      {"navy", {20, 30, 80}},        {"purple", {110, 40, 140}},      {"pink", {240, 120, 170}},
      {"brown", {110, 70, 35}},
  };
}

}  // namespace netlab::recon
