#include "libreconstruct/labeling/label_identity.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "libreconstruct/coloring/yarn_coloring.h"

namespace netlab::recon {
namespace {

constexpr const char* kSlotNames[4] = {"right", "down", "left", "up"};

// The knot's slots (right, down, left, up) that the net has, from its grid position.
std::array<bool, 4> PresentSlots(int row, int col, int rows, int cols) {
  return {col + 1 < cols, row + 1 < rows, col > 0, row > 0};
}

bool Contains(const std::vector<int>& v, int x) {
  return std::find(v.begin(), v.end(), x) != v.end();
}

// True when the yarns and the knot's links can be paired one to one, each pair's link dye
// plausible for its yarn: every yarn a distinct link when there are at most as many yarns as
// links, every link a distinct yarn when there are more (a spurious branch). Brute force over
// the orders of the larger side (<= 4! = 24).
bool FitsDistinctLinks(const std::vector<int>& links,
                       const std::vector<std::vector<int>>& plausible) {
  const size_t n = plausible.size(), d = links.size();
  std::vector<int> order(std::max(n, d));
  for (size_t i = 0; i < order.size(); ++i) order[i] = static_cast<int>(i);
  do {
    bool fits = true;
    for (size_t i = 0; i < std::min(n, d) && fits; ++i)
      fits = n <= d ? Contains(plausible[i], links[order[i]])
                    : Contains(plausible[order[i]], links[i]);
    if (fits) return true;
  } while (std::next_permutation(order.begin(), order.end()));
  return false;
}

std::string KnotName(int row, int col) {
  char text[32];
  std::snprintf(text, sizeof(text), "(%d, %d)", row, col);
  return text;
}

// "orange", "orange/pink" (ambiguous), "?" (not read), "no thread" (too few thread samples).
std::string ReadingName(const YarnReading& r, const KnotCodebook& codebook, bool read,
                        int min_samples) {
  if (!read) return r.samples < min_samples ? "no thread" : "?";
  std::string text;
  for (int c : r.plausible) text += (text.empty() ? "" : "/") + codebook.palette[c].name;
  return text;
}

// The radius (px) out to which a solid covers the knot: the last of the rings r = 2, 3, ... up to
// max_radius_px, contiguous from the knot, on which at least `occupancy` of the pixels differ from
// the background (the median of the ring at background_radius_px) by min_contrast (RMS over the
// channels, linear 0..1). 0 when the first ring is clear; > max_radius_px when the solid is
// larger; -1 when the rings leave the image.
double SolidRadius(const cv::Mat& bgr8, const Eigen::Vector2d& px, double background_radius_px,
                   double max_radius_px, const IdentifyOptions& o, double occupancy) {
  float lut[256];
  for (int v = 0; v < 256; ++v)
    lut[v] = static_cast<float>(o.image_is_linear ? v / 255.0 : SrgbToLinear(v / 255.0));
  // Pixels at the ring's points (pixel centres: a solid's rim is sharp enough for this).
  auto ring = [&](double radius, std::vector<Colour>* out) {
    const int n = std::max(16, static_cast<int>(std::ceil(2 * std::numbers::pi * radius)));
    out->clear();
    for (int i = 0; i < n; ++i) {
      const double a = 2 * std::numbers::pi * i / n;
      const int x = static_cast<int>(std::lround(px.x() + radius * std::cos(a)));
      const int y = static_cast<int>(std::lround(px.y() + radius * std::sin(a)));
      if (x < 0 || y < 0 || x >= bgr8.cols || y >= bgr8.rows) return false;
      const cv::Vec3b& p = bgr8.at<cv::Vec3b>(y, x);
      out->push_back(Colour(lut[p[0]], lut[p[1]], lut[p[2]]));
    }
    return true;
  };
  std::vector<Colour> pixels;
  if (!ring(background_radius_px, &pixels)) return -1;
  Colour background;
  for (int c = 0; c < 3; ++c) {
    std::vector<float> v;
    for (const Colour& p : pixels) v.push_back(p[c]);
    std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
    background[c] = v[v.size() / 2];
  }
  double rim = 0;
  for (double radius = 2; radius <= max_radius_px + 1; radius += 1) {
    if (!ring(radius, &pixels)) return -1;
    int covered = 0;
    for (const Colour& p : pixels) {
      const Colour d = p - background;
      covered += std::sqrt((d[0] * d[0] + d[1] * d[1] + d[2] * d[2]) / 3.0) >= o.min_contrast;
    }
    if (covered < occupancy * static_cast<double>(pixels.size())) break;
    rim = radius;
  }
  return rim;
}

// The labeled knot, checked against the codebook.
struct LabeledKnot {
  const CodebookKnot* knot = nullptr;
  std::array<bool, 4> present{};  // the slots (right, down, left, up) the net has at it
  int degree = 0;                 // its links
  std::string name;               // "(row, col)"
};

// Checks the arguments of CheckIdentity (std::invalid_argument or std::out_of_range naming what
// is wrong) and returns the labeled knot. The net's shape from the codebook's last knot;
// row-major order is checked at the knot in question (O(1): this runs once per label).
LabeledKnot CheckArguments(const cv::Mat& bgr8, const KnotCodebook& codebook, int knot,
                           const Eigen::Vector2d& px, const IdentityCheckOptions& options) {
  if (bgr8.type() != CV_8UC3)
    throw std::invalid_argument("CheckIdentity: the frame is not CV_8UC3 (type " +
                                std::to_string(bgr8.type()) + ", " +
                                std::to_string(bgr8.channels()) + " channels)");
  if (!px.allFinite()) throw std::invalid_argument("CheckIdentity: the knot's pixel is not finite");
  if (codebook.knots.empty()) throw std::invalid_argument("CheckIdentity: empty codebook");
  const int rows = codebook.knots.back().row + 1, cols = codebook.knots.back().col + 1;
  const int knots = static_cast<int>(codebook.knots.size());
  if (knot < 0 || knot >= knots)
    throw std::out_of_range("CheckIdentity: knot " + std::to_string(knot) +
                            " is not in the net (0.." + std::to_string(knots - 1) + ")");
  LabeledKnot labeled;
  labeled.knot = &codebook.knots[knot];
  labeled.present = PresentSlots(labeled.knot->row, labeled.knot->col, rows, cols);
  labeled.degree =
      static_cast<int>(std::count(labeled.present.begin(), labeled.present.end(), true));
  if (rows * cols != knots || labeled.knot->row != knot / cols ||
      labeled.knot->col != knot % cols || labeled.knot->degree() != labeled.degree)
    throw std::invalid_argument("CheckIdentity: the codebook is not a whole " +
                                std::to_string(rows) + " x " + std::to_string(cols) +
                                " net in row-major order at knot " + std::to_string(knot));
  std::string error;
  if (!options.IsValid(&error)) throw std::invalid_argument("CheckIdentity: " + error);
  labeled.name = KnotName(labeled.knot->row, labeled.knot->col);
  return labeled;
}

// The yarns to read at the knot.
struct YarnsToRead {
  std::vector<Eigen::Vector2d> dirs;  // image, unit
  std::vector<std::string> names;     // "right", ... or "37 deg", ...
  std::vector<int> links;             // each yarn's link (index into link_colours); empty: unknown
};

// The yarns towards the labeled neighbours (their links known) and the shortest link.
struct LabeledNeighbours {
  YarnsToRead yarns;
  double shortest_link_px = std::numeric_limits<double>::infinity();  // image px; inf: none
};

// The labeled neighbours that are at least min_link_px away. Throws std::invalid_argument on a
// neighbour in a slot the knot does not have.
LabeledNeighbours FindLabeledNeighbours(const LabeledKnot& labeled, const Eigen::Vector2d& px,
                                        const YarnDirections& yarns,
                                        const IdentityCheckOptions& options) {
  LabeledNeighbours out;
  for (int s = 0, link = 0; s < 4; ++s) {
    const std::optional<Eigen::Vector2d>& nb = yarns.neighbour_px[s];
    if (!labeled.present[s]) {
      if (nb)
        throw std::invalid_argument("CheckIdentity: knot " + labeled.name + " has no " +
                                    kSlotNames[s] + " neighbour, one was given");
      continue;
    }
    if (nb && nb->allFinite() && (*nb - px).norm() >= options.min_link_px) {
      out.yarns.dirs.push_back((*nb - px).normalized());
      out.yarns.names.push_back(kSlotNames[s]);
      out.yarns.links.push_back(link);
      out.shortest_link_px = std::min(out.shortest_link_px, (*nb - px).norm());
    }
    ++link;
  }
  return out;
}

// The detector's branches in angle order (their links unknown). Throws std::invalid_argument on
// a count outside 2..4 or an angle that is not finite.
YarnsToRead BranchYarns(const std::vector<double>& branch_angles_rad) {
  const int n = static_cast<int>(branch_angles_rad.size());
  if (n < 2 || n > 4)
    throw std::invalid_argument("CheckIdentity: " + std::to_string(n) +
                                " branch angles (need 2..4)");
  std::vector<double> angles = branch_angles_rad;
  for (double& a : angles) {
    if (!std::isfinite(a))
      throw std::invalid_argument("CheckIdentity: a branch angle is not finite");
    a = std::remainder(a, 2 * std::numbers::pi);
  }
  // Angle order is cyclic order around the knot (what the cyclic rule compares).
  std::sort(angles.begin(), angles.end());
  YarnsToRead out;
  for (double a : angles) {
    out.dirs.emplace_back(std::cos(a), std::sin(a));
    char text[32];
    std::snprintf(text, sizeof(text), "%.0f deg", a * 180 / std::numbers::pi);
    out.names.push_back(text);
  }
  return out;
}

// How far along the yarns to read: out to a fraction of the shortest labeled link, from beyond
// any solid at the knot. nullopt, with the reason in *why, when a solid covers the knot out to
// more than half of that.
std::optional<IdentifyOptions> ReadingRange(const cv::Mat& bgr8, const Eigen::Vector2d& px,
                                            double shortest_link_px, const LabeledKnot& labeled,
                                            const IdentityCheckOptions& options, std::string* why) {
  const IdentifyOptions& read_options = options.identify;
  IdentifyOptions reading = read_options;
  reading.candidate_knots.clear();
  if (std::isfinite(shortest_link_px))
    reading.outer_radius_px = std::clamp(options.link_fraction * shortest_link_px,
                                         read_options.outer_radius_px, options.max_outer_radius_px);
  const double solid = SolidRadius(bgr8, px, reading.outer_radius_px, 0.5 * reading.outer_radius_px,
                                   read_options, options.solid_occupancy);
  if (solid > 0.5 * reading.outer_radius_px) {
    char text[160];
    std::snprintf(text, sizeof(text),
                  "a solid covers %s out to more than %.0f px: its yarns are not read",
                  labeled.name.c_str(), 0.5 * reading.outer_radius_px);
    *why = text;
    return std::nullopt;
  }
  if (solid + 2 > reading.inner_radius_px) reading.inner_radius_px = solid + 2;
  return reading;
}

// Each yarn's reading against the labeled knot's links.
struct YarnComparison {
  std::vector<std::vector<int>> plausible;  // each yarn's plausible dyes
  std::string readings;                     // "right orange, down ?, ..."
  std::string contradictions;               // "; "-separated, empty when none
  int certain = 0;                          // yarns read with one plausible dye
  int contradicting = 0;
};

// A known link's dye must be plausible for its read yarn. An unknown link: some dye of the knot
// must be, unless there are more branches than links (this one may be the spurious one).
YarnComparison CompareYarnsWithLinks(const KnotIdentification& id, const LabeledKnot& labeled,
                                     const YarnsToRead& to_read, const KnotCodebook& codebook,
                                     const IdentifyOptions& read_options) {
  const int n = static_cast<int>(to_read.dirs.size());
  const std::vector<int>& links = labeled.knot->link_colours;
  YarnComparison out;
  out.plausible.resize(n);
  for (int y = 0; y < n; ++y) {
    const YarnReading& r = id.yarns[y];
    const bool read = r.best >= 0 && r.best_delta_e <= read_options.max_delta_e;
    out.plausible[y] = r.plausible;
    if (read && r.plausible.size() == 1) ++out.certain;
    out.readings += (out.readings.empty() ? "" : ", ") + to_read.names[y] + " " +
                    ReadingName(r, codebook, read, read_options.min_samples);
    if (!read) continue;
    bool contradicts = true;
    if (!to_read.links.empty()) {
      contradicts = !Contains(r.plausible, links[to_read.links[y]]);
    } else if (n <= labeled.degree) {
      for (int c : links) contradicts = contradicts && !Contains(r.plausible, c);
    } else {
      contradicts = false;
    }
    if (contradicts) {
      ++out.contradicting;
      const std::string wanted = to_read.links.empty()
                                     ? "no link of " + labeled.name + " has it"
                                     : labeled.name + "'s " + to_read.names[y] + " link is " +
                                           codebook.palette[links[to_read.links[y]]].name;
      out.contradictions += (out.contradictions.empty() ? "" : "; ") + to_read.names[y] +
                            " yarn is " + ReadingName(r, codebook, true, 0) + ", " + wanted;
    }
  }
  return out;
}

// The knot as a whole, when the links of the yarns are unknown: the yarns and the links must
// pair up one to one (and in cyclic order under the cyclic rule, as many of each). Distinct
// branches are distinct links whatever the rule (the set rule only means that the codes differ
// as sets); the cyclic rule adds their order. Empty when they do, else how they do not.
std::string WholeKnotMisfit(const KnotCodebook& codebook, int knot, const LabeledKnot& labeled,
                            const std::vector<std::vector<int>>& plausible) {
  const int n = static_cast<int>(plausible.size());
  const std::vector<int>& links = labeled.knot->link_colours;
  const bool cyclic = n == labeled.degree && codebook.rule == CodeRule::kCyclic;
  const bool fits =
      cyclic ? codebook.FitsSomeReading(knot, plausible) : FitsDistinctLinks(links, plausible);
  if (fits) return "";
  std::string code;
  for (int c : links) code += (code.empty() ? "" : " ") + codebook.palette[c].name;
  const std::string& name = labeled.name;
  return cyclic               ? "not the cyclic code of " + name + " (" + code + ")"
         : n > labeled.degree ? "without " + name + "'s links among them (" + code + ")"
                              : "not distinct links of " + name + " (" + code + ")";
}

// "; colours fit (r, c) ..." (the first four), or empty when they fit nothing.
std::string KnotsReadText(const std::vector<int>& knots_read, const KnotCodebook& codebook) {
  std::string said;
  if (!knots_read.empty()) {
    said = "; colours fit ";
    for (size_t i = 0; i < knots_read.size() && i < 4; ++i) {
      const CodebookKnot& k = codebook.knots[knots_read[i]];
      said += (i ? " " : "") + KnotName(k.row, k.col);
    }
    if (knots_read.size() > 4) said += " ...";
  }
  return said;
}

}  // namespace

bool IdentityCheckOptions::IsValid(std::string* error) const {
  auto fail = [&](const std::string& why) {
    if (error) *error = "IdentityCheckOptions: " + why;
    return false;
  };
  if (!identify.IsValid(error)) return false;
  if (!(link_fraction > 0 && link_fraction < 1)) return fail("link_fraction must be in (0, 1)");
  if (!(max_outer_radius_px >= identify.outer_radius_px))
    return fail("max_outer_radius_px must be >= identify.outer_radius_px");
  if (!(solid_occupancy > 0 && solid_occupancy <= 1))
    return fail("solid_occupancy must be in (0, 1]");
  if (min_certain_yarns < 1) return fail("min_certain_yarns must be >= 1");
  if (!(min_link_px > 0)) return fail("min_link_px must be > 0");
  return true;
}

KnotCodebook CodebookFromColoring(const NetColoring& coloring,
                                  const std::vector<std::array<int, 3>>& palette_srgb,
                                  const Lighting& lighting) {
  std::string error;
  if (!lighting.IsValid(&error)) throw std::invalid_argument("CodebookFromColoring: " + error);
  if (coloring.colors < 1 || coloring.rows < 1 || coloring.cols < 1)
    throw std::invalid_argument("CodebookFromColoring: the colouring has no colours or no knots");
  KnotCodebook codebook;
  codebook.rule = coloring.options.rule;
  // The palette as LoadYarnColoring gives it to the renderer (the dye's sRGB, else the default
  // palette in order), then as the camera sees it.
  const YarnColoring fallback = DefaultColoring(2, 2);
  for (int i = 0; i < coloring.colors; ++i) {
    PaletteColour p;
    p.name = i < static_cast<int>(coloring.palette_names.size()) ? coloring.palette_names[i]
                                                                 : "colour " + std::to_string(i);
    if (i < static_cast<int>(palette_srgb.size())) {
      const auto& s = palette_srgb[i];
      p.linear_bgr = lighting.Seen({double(s[0]), double(s[1]), double(s[2])});
    } else {
      const Colour c = fallback.palette[i % fallback.palette.size()];
      for (int k = 0; k < 3; ++k)
        p.linear_bgr[k] = static_cast<float>(
            std::clamp(lighting.exposure * lighting.gains_bgr[k] * c[k], 0.0, 1.0));
    }
    codebook.palette.push_back(p);
  }
  for (int r = 0; r < coloring.rows; ++r)
    for (int c = 0; c < coloring.cols; ++c)
      codebook.knots.push_back({r, c, KnotLinkColours(coloring, r, c)});
  return codebook;
}

std::string IdentityVerdictName(IdentityVerdict verdict) {
  switch (verdict) {
    case IdentityVerdict::kConsistent: return "consistent";
    case IdentityVerdict::kMismatch: return "mismatch";
    case IdentityVerdict::kUnreadable: return "unreadable";
  }
  return "?";
}

IdentityCheck CheckIdentity(const cv::Mat& bgr8, const KnotCodebook& codebook, int knot,
                            const Eigen::Vector2d& px, const YarnDirections& yarns,
                            const IdentityCheckOptions& options) {
  const LabeledKnot labeled = CheckArguments(bgr8, codebook, knot, px, options);
  IdentityCheck result;

  // The labeled neighbours: directions (with their links) and the shortest link's image length.
  const LabeledNeighbours neighbours = FindLabeledNeighbours(labeled, px, yarns, options);

  // The yarn directions: the detector's branches in angle order (their links unknown), else the
  // neighbours'.
  const YarnsToRead to_read =
      yarns.branch_angles_rad.empty() ? neighbours.yarns : BranchYarns(yarns.branch_angles_rad);
  const int n = static_cast<int>(to_read.dirs.size());
  result.yarns = n;
  if (n < 2) {
    result.why = "only " + std::to_string(n) + " yarn direction(s) for " + labeled.name +
                 " (labeled neighbours at least " +
                 std::to_string(static_cast<int>(options.min_link_px)) + " px away)";
    return result;
  }

  // How far along the yarns to read (nothing when a solid covers the knot).
  const std::optional<IdentifyOptions> reading =
      ReadingRange(bgr8, px, neighbours.shortest_link_px, labeled, options, &result.why);
  if (!reading) return result;

  // The colours, and what they say over the whole codebook.
  const KnotIdentification id = IdentifyKnot(bgr8, px, to_read.dirs, *reading, codebook);
  if (static_cast<int>(id.yarns.size()) != n) {
    result.why = id.reasons.empty() ? "colours not read" : id.reasons.front();
    return result;
  }
  if (id.status != IdentifyStatus::kUnknown && n == labeled.degree) result.knots_read = id.knots;

  // Each yarn against the labeled knot's links.
  const YarnComparison compared =
      CompareYarnsWithLinks(id, labeled, to_read, codebook, options.identify);
  result.yarns_certain = compared.certain;
  result.yarns_contradicting = compared.contradicting;

  // The knot as a whole, when the links of the yarns are unknown.
  bool fits = result.yarns_contradicting == 0;
  std::string whole;
  if (fits && to_read.links.empty()) {
    whole = WholeKnotMisfit(codebook, knot, labeled, compared.plausible);
    fits = whole.empty();
  }

  // The verdict: a contradiction, too few yarns read with certainty, or consistent.
  const std::string said = KnotsReadText(result.knots_read, codebook);
  const std::string& name = labeled.name;
  if (!fits) {
    result.verdict = IdentityVerdict::kMismatch;
    result.why = "label " + name + " contradicted by its colours: " +
                 (compared.contradictions.empty() ? compared.readings + " are " + whole
                                                  : compared.contradictions) +
                 said;
  } else if (result.yarns_certain < std::min(options.min_certain_yarns, labeled.degree)) {
    result.verdict = IdentityVerdict::kUnreadable;
    result.why = std::to_string(result.yarns_certain) + " yarn colour(s) read with certainty (" +
                 compared.readings + ")";
  } else {
    result.verdict = IdentityVerdict::kConsistent;
    result.why = compared.readings + ": fit " + name + said;
  }
  return result;
}

JunctionReading ReadJunctionIdentity(const cv::Mat& bgr8, const KnotCodebook& codebook,
                                     const Eigen::Vector2d& px,
                                     const std::vector<double>& branch_angles_rad, double link_px,
                                     const IdentityCheckOptions& options,
                                     const std::vector<int>& exclude) {
  // The arguments, checked as CheckIdentity's (at knot 0: the codebook's shape).
  LabeledKnot junction = CheckArguments(bgr8, codebook, 0, px, options);
  junction.name = "the junction";
  const YarnsToRead to_read = BranchYarns(branch_angles_rad);
  const int n = static_cast<int>(to_read.dirs.size());
  JunctionReading result;
  result.yarns = n;

  // How far along the yarns to read (nothing when a solid covers the junction).
  const double link =
      link_px > 0 && std::isfinite(link_px) ? link_px : std::numeric_limits<double>::infinity();
  const std::optional<IdentifyOptions> reading =
      ReadingRange(bgr8, px, link, junction, options, &result.why);
  if (!reading) return result;
  const KnotIdentification id = IdentifyKnot(bgr8, px, to_read.dirs, *reading, codebook);
  if (static_cast<int>(id.yarns.size()) != n) {
    result.why = id.reasons.empty() ? "colours not read" : id.reasons.front();
    return result;
  }

  // Each yarn's plausible dyes (all of them when it is not read).
  const IdentifyOptions& o = options.identify;
  std::vector<int> every(codebook.palette.size());
  for (size_t i = 0; i < every.size(); ++i) every[i] = static_cast<int>(i);
  std::vector<std::vector<int>> plausible(n);
  std::string readings;
  int read_yarns = 0;
  for (int y = 0; y < n; ++y) {
    const YarnReading& r = id.yarns[y];
    const bool read = r.best >= 0 && r.best_delta_e <= o.max_delta_e && !r.plausible.empty();
    read_yarns += read;
    plausible[y] = read ? r.plausible : every;
    result.yarns_certain += read && r.plausible.size() == 1;
    readings += (readings.empty() ? "" : ", ") + to_read.names[y] + " " +
                ReadingName(r, codebook, read, o.min_samples);
  }

  if (read_yarns == 0) {  // every knot would fit: say so instead of offering the whole net
    result.why = "no yarn colour read (" + readings + ")";
    return result;
  }

  // Every knot the readings fit, minus those excluded.
  int fitting = 0;
  for (int k = 0; k < static_cast<int>(codebook.knots.size()); ++k) {
    const CodebookKnot& knot = codebook.knots[k];
    const bool cyclic = codebook.rule == CodeRule::kCyclic && n == knot.degree();
    const bool fits = cyclic ? codebook.FitsSomeReading(k, plausible)
                             : FitsDistinctLinks(knot.link_colours, plausible);
    if (!fits) continue;
    ++fitting;
    if (Contains(exclude, k))
      ++result.excluded;
    else
      result.knots.push_back(k);
  }
  const int needed = std::min(options.min_certain_yarns, n);
  char counts[160];
  std::snprintf(counts, sizeof(counts), " (%d of %d yarns read with certainty; %d knot(s) fit",
                result.yarns_certain, n, fitting);
  std::string tail = counts;
  if (result.excluded > 0) tail += ", " + std::to_string(result.excluded) + " labeled elsewhere";
  tail += ")";
  if (result.knots.empty()) {
    result.status = IdentifyStatus::kUnknown;
    result.why = readings + ": no knot of the net fits" + tail;
  } else if (result.knots.size() == 1 && result.yarns_certain >= needed) {
    result.status = IdentifyStatus::kIdentified;
    const CodebookKnot& k = codebook.knots[result.knots[0]];
    result.why = readings + ": only " + KnotName(k.row, k.col) + " fits" + tail;
  } else if (result.knots.size() == 1) {
    result.status = IdentifyStatus::kAmbiguous;
    const CodebookKnot& k = codebook.knots[result.knots[0]];
    result.why = readings + ": only " + KnotName(k.row, k.col) +
                 " fits, but too few yarns are read with certainty to be sure" + tail;
  } else {
    result.status = IdentifyStatus::kAmbiguous;
    std::string some;
    for (size_t i = 0; i < result.knots.size() && i < 4; ++i) {
      const CodebookKnot& k = codebook.knots[result.knots[i]];
      some += " " + KnotName(k.row, k.col);
    }
    if (result.knots.size() > 4) some += " ...";
    result.why = readings + ": " + std::to_string(result.knots.size()) + " knots fit" + some + tail;
  }
  return result;
}

}  // namespace netlab::recon
