#include "libreconstruct/coloring/net_coloring.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <deque>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <map>
#include <random>
#include <set>
#include <span>
#include <sstream>
#include <stdexcept>
#include <unordered_map>

#include "common/files.h"
#include "common/yaml_util.h"

namespace netlab::recon {
namespace {

using Clock = std::chrono::steady_clock;

double Since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

// Link colours of one knot in geometric order; unused slots are -1.
struct Cfg {
  int d = 0;
  std::array<int, 4> c{-1, -1, -1, -1};
};

// A link whose colour is left open (keys of the distance-2 search and of the packing bound).
constexpr int kWildColour = 254;

// The dihedral images of a cyclic sequence of length d (2d of them, d = 1: one).
int DihedralImages(const Cfg& x, std::array<Cfg, 8>* out) {
  if (x.d <= 1) {
    (*out)[0] = x;
    return 1;
  }
  int n = 0;
  for (int mirror = 0; mirror < 2; ++mirror)
    for (int rot = 0; rot < x.d; ++rot) {
      Cfg y;
      y.d = x.d;
      for (int i = 0; i < x.d; ++i) {
        const int j = mirror ? (rot - i + 2 * x.d) % x.d : (rot + i) % x.d;
        y.c[i] = x.c[j];
      }
      (*out)[n++] = y;
    }
  return n;
}

Cfg Canonical(CodeRule rule, const Cfg& x) {
  Cfg y = x;
  switch (rule) {
    case CodeRule::kSet: {
      std::sort(y.c.begin(), y.c.begin() + y.d);
      y.d = static_cast<int>(std::unique(y.c.begin(), y.c.begin() + y.d) - y.c.begin());
      for (int i = y.d; i < 4; ++i) y.c[i] = -1;
      return y;
    }
    case CodeRule::kMultiset: std::sort(y.c.begin(), y.c.begin() + y.d); return y;
    case CodeRule::kCyclic: {
      std::array<Cfg, 8> images;
      const int n = DihedralImages(x, &images);
      for (int i = 1; i < n; ++i)
        if (images[i].c < y.c) y = images[i];
      return y;
    }
  }
  return y;
}

// Packs degree and canonical code into one key (colours < 255).
uint64_t CodeKey(CodeRule rule, const Cfg& x) {
  const Cfg y = Canonical(rule, x);
  uint64_t key = static_cast<uint64_t>(x.d);
  for (int i = 0; i < 4; ++i) key = (key << 8) | static_cast<uint64_t>(y.c[i] + 1);
  return key;
}

// Change(x -> S) for the set rule: links of x not in S must change; colours of S missing from x
// must be created; both fit in the same changes while |S| <= d.
int SetChange(const Cfg& x, const Cfg& s /* canonical set */) {
  if (s.d > x.d) return kFarDistance;
  int out = 0;
  uint64_t present = 0;
  for (int i = 0; i < x.d; ++i) {
    bool in = false;
    for (int j = 0; j < s.d; ++j) in = in || s.c[j] == x.c[i];
    if (in)
      present |= uint64_t{1} << x.c[i];
    else
      ++out;
  }
  const int missing = s.d - __builtin_popcountll(present);
  return std::max(out, missing);
}

int Distance(CodeRule rule, const Cfg& a, const Cfg& b) {
  if (a.d != b.d) return kFarDistance;
  switch (rule) {
    case CodeRule::kSet:
      return std::min(SetChange(a, Canonical(rule, b)), SetChange(b, Canonical(rule, a)));
    case CodeRule::kMultiset: {
      std::array<int, 4> x = a.c, y = b.c;
      std::sort(x.begin(), x.begin() + a.d);
      std::sort(y.begin(), y.begin() + b.d);
      int i = 0, j = 0, common = 0;
      while (i < a.d && j < b.d) {
        if (x[i] == y[j])
          ++common, ++i, ++j;
        else if (x[i] < y[j])
          ++i;
        else
          ++j;
      }
      return a.d - common;
    }
    case CodeRule::kCyclic: {
      std::array<Cfg, 8> images;
      const int n = DihedralImages(b, &images);
      int best = kFarDistance;
      for (int k = 0; k < n; ++k) {
        int h = 0;
        for (int i = 0; i < a.d; ++i) h += a.c[i] != images[k].c[i];
        best = std::min(best, h);
      }
      return best;
    }
  }
  return kFarDistance;
}

Cfg ToCfg(const std::vector<int>& v) {
  if (v.size() > 4) throw std::invalid_argument("a knot has at most 4 links");
  Cfg x;
  x.d = static_cast<int>(v.size());
  for (int i = 0; i < x.d; ++i) x.c[i] = v[i];
  return x;
}

int64_t Binomial(int64_t n, int64_t k) {
  if (k < 0 || n < k) return 0;
  int64_t r = 1;
  for (int64_t i = 1; i <= k; ++i) r = r * (n - k + i) / i;
  return r;
}

// The packing bound for D >= 2 (see MaxCodePacking): a linear programme over code patterns.
//
// Give every code its KEYS: the code with D - 1 of its links wildcarded (canonical under the
// rule). Two codes within D - 1 changes of each other share a key (wildcard the links where the
// best alignment differs), so codes pairwise >= D apart own disjoint key sets. Count codes and
// keys per PATTERN (a code or key up to renaming of the colours: aabc, abab, ab*c, ...): colour
// renaming maps valid packings to valid packings, so the LP "as many codes as possible, every
// key class used at most as often as it has keys" may be averaged over renamings and has one
// variable per code pattern and one constraint per key pattern. Its optimum bounds the packing.

// Positions-group images of a configuration: the dihedral group (cyclic), every permutation
// (multiset; 24 at most).
std::vector<Cfg> PositionImages(CodeRule rule, const Cfg& x) {
  std::vector<Cfg> out;
  if (rule == CodeRule::kCyclic) {
    std::array<Cfg, 8> images;
    const int n = DihedralImages(x, &images);
    out.assign(images.begin(), images.begin() + n);
    return out;
  }
  std::array<int, 4> p{0, 1, 2, 3};
  do {
    Cfg y = x;
    for (int i = 0; i < x.d; ++i) y.c[i] = x.c[p[i]];
    out.push_back(y);
  } while (std::next_permutation(p.begin(), p.begin() + x.d));
  return out;
}

// Colours renamed in order of first appearance (the wildcard kept).
Cfg Renamed(const Cfg& x) {
  std::array<int, 256> name;
  name.fill(-1);
  int next = 0;
  Cfg y = x;
  for (int i = 0; i < x.d; ++i) {
    if (x.c[i] == kWildColour) continue;
    if (name[x.c[i]] < 0) name[x.c[i]] = next++;
    y.c[i] = name[x.c[i]];
  }
  return y;
}

// The pattern of a configuration: least renamed image under the position group.
std::array<int, 4> Pattern(CodeRule rule, const Cfg& x) {
  std::array<int, 4> best{};
  bool first = true;
  for (const Cfg& y : PositionImages(rule, x)) {
    const std::array<int, 4> r = Renamed(y).c;
    if (first || r < best) best = r, first = false;
  }
  return best;
}

// How many distinct sequences the position group makes of x (colours as given).
int OrbitSize(CodeRule rule, const Cfg& x) {
  std::vector<std::array<int, 4>> seen;
  for (const Cfg& y : PositionImages(rule, x)) seen.push_back(y.c);
  std::sort(seen.begin(), seen.end());
  return static_cast<int>(std::unique(seen.begin(), seen.end()) - seen.begin());
}

double Falling(int k, int j) {
  double r = 1;
  for (int i = 0; i < j; ++i) r *= k - i;
  return std::max(r, 0.0);
}

// Every assignment of the positions in `free` (others -1) to colours 0.. in order of first
// appearance (restricted growth strings); all distinct only when `distinct`.
void ForEachRenamedFilling(const Cfg& base, const std::vector<int>& free, bool distinct,
                           const std::function<void(const Cfg&, int)>& visit) {
  Cfg x = base;
  std::function<void(size_t, int)> rec = [&](size_t i, int used) {
    if (i == free.size()) {
      visit(x, used);
      return;
    }
    for (int c = distinct ? used : 0; c <= used; ++c) {
      x.c[free[i]] = c;
      rec(i + 1, std::max(used, c + 1));
    }
  };
  rec(0, 0);
}

// max sum(y) subject to A y <= b, y >= 0, with b >= 0 (the origin is feasible): dense simplex,
// Bland's rule. Small problems only (a few dozen rows).
double MaximiseSum(const std::vector<std::vector<double>>& a, const std::vector<double>& b) {
  const int m = static_cast<int>(a.size());
  const int n = m > 0 ? static_cast<int>(a[0].size()) : 0;
  // Tableau rows 0..m-1: [A | I | b]; row m: objective (reduced costs, negated).
  std::vector<std::vector<double>> t(m + 1, std::vector<double>(n + m + 1, 0.0));
  std::vector<int> basis(m);
  for (int i = 0; i < m; ++i) {
    for (int j = 0; j < n; ++j) t[i][j] = a[i][j];
    t[i][n + i] = 1;
    t[i][n + m] = b[i];
    basis[i] = n + i;
  }
  for (int j = 0; j < n; ++j) t[m][j] = -1;
  constexpr double kEps = 1e-9;
  while (true) {
    int enter = -1;
    for (int j = 0; j < n + m && enter < 0; ++j)
      if (t[m][j] < -kEps) enter = j;
    if (enter < 0) break;
    int leave = -1;
    double best = 0;
    for (int i = 0; i < m; ++i) {
      if (t[i][enter] <= kEps) continue;
      const double r = t[i][n + m] / t[i][enter];
      if (leave < 0 || r < best - kEps || (r < best + kEps && basis[i] < basis[leave]))
        leave = i, best = r;
    }
    if (leave < 0) return std::numeric_limits<double>::infinity();  // unbounded
    const double p = t[leave][enter];
    for (double& v : t[leave]) v /= p;
    for (int i = 0; i <= m; ++i) {
      if (i == leave || std::abs(t[i][enter]) <= 0) continue;
      const double f = t[i][enter];
      for (int j = 0; j <= n + m; ++j) t[i][j] -= f * t[leave][j];
    }
    basis[leave] = enter;
  }
  return t[m][n + m];
}

int64_t PatternPackingBound(CodeRule rule, int degree, int k, bool distinct, int min_distance) {
  const int w = min_distance - 1;  // wildcards per key
  std::vector<int> all(degree);
  for (int i = 0; i < degree; ++i) all[i] = i;
  Cfg empty;
  empty.d = degree;
  // Code patterns: how many codes, and a representative.
  std::map<std::array<int, 4>, std::pair<double, Cfg>> codes;
  ForEachRenamedFilling(empty, all, distinct, [&](const Cfg& x, int used) {
    auto& entry = codes[Pattern(rule, x)];
    entry.first += Falling(k, used) / OrbitSize(rule, x);
    entry.second = x;
  });
  // Key patterns: how many keys.
  std::map<std::array<int, 4>, double> keys;
  for (int mask = 0; mask < (1 << degree); ++mask) {
    if (__builtin_popcount(mask) != w) continue;
    Cfg base = empty;
    std::vector<int> free;
    for (int i = 0; i < degree; ++i) {
      if (mask & (1 << i))
        base.c[i] = kWildColour;
      else
        free.push_back(i);
    }
    ForEachRenamedFilling(base, free, distinct, [&](const Cfg& x, int used) {
      keys[Pattern(rule, x)] += Falling(k, used) / OrbitSize(rule, x);
    });
  }
  // Per code pattern, its distinct keys by key pattern.
  std::vector<std::array<int, 4>> key_index;
  for (const auto& [p, n] : keys) key_index.push_back(p);
  std::vector<std::vector<double>> a;
  std::vector<double> b;
  for (const auto& [p, n] : keys) {
    a.emplace_back(codes.size(), 0.0);
    b.push_back(n);
  }
  int t = 0;
  for (const auto& [p, entry] : codes) {
    const Cfg& x = entry.second;
    std::set<std::array<int, 4>> own;
    for (int mask = 0; mask < (1 << degree); ++mask) {
      if (__builtin_popcount(mask) != w) continue;
      Cfg y = x;
      for (int i = 0; i < degree; ++i)
        if (mask & (1 << i)) y.c[i] = kWildColour;
      own.insert(Canonical(rule, y).c);
    }
    for (const auto& key : own) {
      Cfg y;
      y.d = degree;
      y.c = key;
      const size_t s = std::lower_bound(key_index.begin(), key_index.end(), Pattern(rule, y)) -
                       key_index.begin();
      a[s][t] += 1;
    }
    // y_t <= number of codes of this pattern.
    std::vector<double> row(codes.size(), 0.0);
    row[t] = 1;
    a.push_back(row);
    b.push_back(entry.first);
    ++t;
  }
  const double opt = MaximiseSum(a, b);
  return static_cast<int64_t>(std::floor(opt + 1e-6));
}

// Same-degree knots within `radius` links of knot x (radius 0: the whole net), in increasing
// order. On the full grid the graph distance is |dr| + |dc|, so the knots within R links are
// the diamond around x, enumerated directly (O(R^2), not O(n)).
template <typename Visit>
void ForEachPartner(int rows, int cols, const std::vector<int>& degree, int radius, int x,
                    Visit visit) {
  const int r = x / cols, c = x % cols;
  const int reach = radius == 0 ? rows + cols : radius;
  for (int wr = std::max(0, r - reach); wr <= std::min(rows - 1, r + reach); ++wr) {
    const int span = reach - std::abs(wr - r);
    for (int wc = std::max(0, c - span); wc <= std::min(cols - 1, c + span); ++wc) {
      const int w = wr * cols + wc;
      if (w != x && degree[w] == degree[x]) visit(w);
    }
  }
}

// How many knots a diamond of radius R holds at most (radius 0: the whole net), less one.
int64_t PartnersPerKnot(int rows, int cols, int radius) {
  const int64_t n = int64_t{rows} * cols;
  if (radius == 0) return n - 1;
  const int64_t r = radius;
  return std::min(n - 1, 2 * r * r + 2 * r);
}

// The fixed structure of the net under the options: links per knot, constrained partners.
struct Net {
  int rows = 0, cols = 0, n = 0, links = 0;
  std::vector<std::array<int, 4>> knot_links;  // geometric order, -1 padded
  std::vector<int> degree;
  std::vector<std::array<int, 2>> link_knots;
  // Same degree, within the radius (all when radius 0): knot x's are
  // partner_list[partner_begin[x] .. partner_begin[x + 1]). Built only for the searches that
  // read them (NeedsPartners): at radius 0 they are n^2 ints.
  std::vector<int64_t> partner_begin;
  std::vector<int> partner_list;

  std::span<const int> partners(int x) const {
    return {partner_list.data() + partner_begin[x],
            static_cast<size_t>(partner_begin[x + 1] - partner_begin[x])};
  }
};

// The heuristics with hashed codes (distance 1) or keys (distance 2) over the whole net never
// compare knots pairwise; the general search and the exact search do.
bool HeuristicNeedsPartners(const ColoringOptions& o) {
  return !(o.radius == 0 && (o.min_distance == 1 || o.min_distance == 2));
}

bool RunsExactStage(int rows, int cols) { return int64_t{rows} * cols <= kExactSearchMaxKnots; }

Net BuildNet(int rows, int cols, const ColoringOptions& o, bool with_partners) {
  Net net;
  net.rows = rows;
  net.cols = cols;
  net.n = rows * cols;
  net.links = NumLinks(rows, cols);
  net.knot_links.resize(net.n);
  net.degree.resize(net.n);
  for (int r = 0; r < rows; ++r)
    for (int c = 0; c < cols; ++c) {
      const std::vector<int> l = KnotLinks(rows, cols, r, c);
      std::array<int, 4> a{-1, -1, -1, -1};
      std::copy(l.begin(), l.end(), a.begin());
      net.knot_links[r * cols + c] = a;
      net.degree[r * cols + c] = static_cast<int>(l.size());
    }
  net.link_knots.reserve(net.links);
  for (int l = 0; l < net.links; ++l) {
    const auto k = LinkKnots(rows, cols, l);
    net.link_knots.push_back({k[0] * cols + k[1], k[2] * cols + k[3]});
  }
  net.partner_begin.assign(net.n + 1, 0);
  if (!with_partners) return net;
  net.partner_list.reserve(static_cast<size_t>(net.n) * PartnersPerKnot(rows, cols, o.radius));
  for (int x = 0; x < net.n; ++x) {
    net.partner_begin[x] = static_cast<int64_t>(net.partner_list.size());
    ForEachPartner(rows, cols, net.degree, o.radius, x,
                   [&](int w) { net.partner_list.push_back(w); });
  }
  net.partner_begin[net.n] = static_cast<int64_t>(net.partner_list.size());
  return net;
}

Cfg KnotCfg(const Net& net, const std::vector<int>& colour, int x) {
  Cfg y;
  y.d = net.degree[x];
  for (int i = 0; i < y.d; ++i) y.c[i] = colour[net.knot_links[x][i]];
  return y;
}

int AdjacentPairs(const Cfg& x) {
  int p = 0;
  for (int i = 0; i < x.d; ++i)
    for (int j = i + 1; j < x.d; ++j) p += x.c[i] == x.c[j];
  return p;
}

// The configurations of link e's two knots (cfg[u], cfg[v]) after e takes colour c.
std::pair<Cfg, Cfg> MovedCfgs(const Net& net, const std::vector<Cfg>& cfg, int e, int c) {
  const int u = net.link_knots[e][0], v = net.link_knots[e][1];
  Cfg cu = cfg[u], cv = cfg[v];
  for (int i = 0; i < cu.d; ++i)
    if (net.knot_links[u][i] == e) cu.c[i] = c;
  for (int i = 0; i < cv.d; ++i)
    if (net.knot_links[v][i] == e) cv.c[i] = c;
  return {cu, cv};
}

// A uniformly random start: every link one of k colours.
std::vector<int> RandomColouring(const Net& net, int k, std::mt19937_64& rng) {
  std::uniform_int_distribution<int> colour_dist(0, k - 1);
  std::vector<int> colour(net.links);
  for (int& c : colour) c = colour_dist(rng);
  return colour;
}

// What a search may still spend: work, the budget that decides the result (counted in the
// search's own steps: code or key evaluations, or exact-search nodes, so that the result does not
// depend on the machine's load), and the wall-clock cap, which only stops a search the work
// budget would have let go on (and records that it did: only then can the result differ between
// runs).
struct Budget {
  int64_t work = 0;
  Clock::time_point deadline;
  bool capped = false;
  int64_t calls = 0;

  // False (and capped set when it was the clock) when the search must stop before spending
  // `units` more; the clock is read every 64th call.
  bool Spend(int64_t units) {
    if (work <= 0) return false;
    work -= units;
    if ((++calls & 63) == 0 && Clock::now() > deadline) capped = true;
    return !capped;
  }
};

// The tabu min-conflicts loop shared by the cost models below: pick a knot in conflict, move
// one of its links to the colour that lowers the cost most (ties at random; a move back is tabu
// for a while unless it beats the best cost seen; 3 % random walk), until the cost is 0 or the
// budget is spent. Model: int64_t cost() const, bool Conflicted(int knot),
// int64_t Delta(int link, int colour), void Apply(int link, int colour), int Colour(int link),
// bool Movable(int link).
// The list of knots in conflict is rebuilt every `refresh_every` moves (a pass over the net, so
// only as often as it costs about what the moves between cost) and extended after each move with
// the moved knots still in conflict: every conflicting pair keeps a knot in the list.
// Each move spends its evaluations (links x other colours, each model.EvalWork() units), each
// rebuild n x model.ScanWork(). The tabu tenures are move numbers in 32 bits: links x colours of
// them are the search's largest array.
template <typename Model>
bool TabuSearch(const Net& net, int k, Model& model, std::mt19937_64& rng, Budget& budget,
                int64_t refresh_every) {
  std::vector<int32_t> tabu(static_cast<size_t>(net.links) * k, -1);
  std::vector<int> conflicted;
  int64_t best_cost = model.cost();
  const int64_t move_work = 4 * (k - 1) * model.EvalWork();
  for (int32_t iter = 0; model.cost() > 0; ++iter) {
    if (iter == INT32_MAX || !budget.Spend(move_work)) return false;
    if (iter % refresh_every == 0 || conflicted.empty()) {
      budget.work -= net.n * model.ScanWork();
      conflicted.clear();
      for (int x = 0; x < net.n; ++x)
        if (model.Conflicted(x)) conflicted.push_back(x);
      if (conflicted.empty()) return false;  // cannot happen while cost > 0; defensive
    }
    const size_t pick = rng() % conflicted.size();
    const int x = conflicted[pick];
    if (!model.Conflicted(x)) {
      conflicted[pick] = conflicted.back();
      conflicted.pop_back();
      continue;
    }
    int best_link = -1, best_c = -1, ties = 0;
    int64_t best_delta = 0;
    const bool random_walk = (rng() % 100) < 3;
    for (int i = 0; i < net.degree[x]; ++i) {
      const int e = net.knot_links[x][i];
      if (!model.Movable(e)) continue;
      for (int c = 0; c < k; ++c) {
        if (c == model.Colour(e)) continue;
        const bool is_tabu = tabu[static_cast<size_t>(e) * k + c] > iter;
        if (is_tabu && random_walk) continue;
        const int64_t delta = random_walk ? 0 : model.Delta(e, c);
        if (is_tabu && model.cost() + delta >= best_cost) continue;
        if (best_link < 0 || delta < best_delta) {
          best_link = e, best_c = c, best_delta = delta, ties = 1;
        } else if (delta == best_delta && rng() % ++ties == 0) {
          best_link = e, best_c = c;
        }
      }
    }
    if (best_link < 0) continue;
    const int64_t tenure = 5 + static_cast<int64_t>(rng() % 10) +
                           static_cast<int64_t>(std::min<size_t>(conflicted.size() / 4, 1 << 24));
    tabu[static_cast<size_t>(best_link) * k + model.Colour(best_link)] =
        static_cast<int32_t>(std::min<int64_t>(iter + tenure, INT32_MAX));
    model.Apply(best_link, best_c);
    best_cost = std::min(best_cost, model.cost());
    for (int y : net.link_knots[best_link])
      if (model.Conflicted(y)) conflicted.push_back(y);
  }
  return true;
}

// Runs a cost model (TabuSearch's, plus Start(colour, active knots, movable links) and
// colours()) from random colourings until the deadline. With `border_first` on a net with both
// border knots (2 or 3 links) and inner ones, in two phases: the border knots alone first (the
// tight part of the experiment nets at D = 2: 60 three-link knots of 17 x 17 need 17 colours,
// the 225 inner ones 15), then the inner links with every link at the border frozen (the inner
// knots have room to spare wherever the border is the tight part).
template <typename Model>
bool SearchBorderFirst(const Net& net, int k, Model& model, std::mt19937_64& rng, Budget& budget,
                       int64_t refresh_every, bool border_first, std::vector<int>* out) {
  const std::vector<char> all_knots(net.n, 1), all_links(net.links, 1);
  std::vector<char> border(net.n), inner_links(net.links);
  bool any_border = false, any_inner = false;
  for (int x = 0; x < net.n; ++x) {
    border[x] = net.degree[x] < 4;
    (border[x] ? any_border : any_inner) = true;
  }
  for (int e = 0; e < net.links; ++e)
    inner_links[e] = !border[net.link_knots[e][0]] && !border[net.link_knots[e][1]];
  if (!border_first || !any_border || !any_inner) {
    if (!model.Start(RandomColouring(net, k, rng), all_knots, all_links, budget)) return false;
    if (!TabuSearch(net, k, model, rng, budget, refresh_every)) return false;
    *out = model.colours();
    return true;
  }
  if (!model.Start(RandomColouring(net, k, rng), border, all_links, budget)) return false;
  if (!TabuSearch(net, k, model, rng, budget, refresh_every)) return false;
  std::vector<int> colour = RandomColouring(net, k, rng);
  for (int e = 0; e < net.links; ++e)
    if (!inner_links[e]) colour[e] = model.colours()[e];
  if (!model.Start(colour, all_knots, inner_links, budget)) return false;
  if (!TabuSearch(net, k, model, rng, budget, refresh_every)) return false;
  *out = model.colours();
  return true;
}

// How often the hashed searches rebuild their list of knots in conflict: a move costs a few hash
// operations, a rebuild one per knot, so every n / 16 moves (at least 64).
int64_t RefreshEvery(const Net& net) { return std::max<int64_t>(64, net.n / 16); }

// What both cost models keep, and the part of TabuSearch's interface that is the same for both:
// the colouring, its knots' configurations, the cost, which knots count (active) and which links
// the search may change (movable).
class CostModel {
 public:
  int64_t cost() const { return cost_; }
  int Colour(int link) const { return colour_[link]; }
  bool Movable(int link) const { return movable_[link] != 0; }
  const std::vector<int>& colours() const { return colour_; }

 protected:
  CostModel(const Net& net, const ColoringOptions& o, int k, uint64_t seed)
      : net_(net), o_(o), k_(k), rng_(seed) {}
  // Takes the colouring and the masks; the configurations are recomputed.
  void Reset(std::vector<int> colour, std::vector<char> active, std::vector<char> movable) {
    colour_ = std::move(colour);
    active_ = std::move(active);
    movable_ = std::move(movable);
    cfg_.resize(net_.n);
    for (int x = 0; x < net_.n; ++x) cfg_[x] = KnotCfg(net_, colour_, x);
    cost_ = 0;
  }

  const Net& net_;
  const ColoringOptions& o_;
  int k_;
  std::mt19937_64 rng_;
  std::vector<int> colour_;
  std::vector<char> active_;   // per knot: its code counts
  std::vector<char> movable_;  // per link: the search may change it
  std::vector<Cfg> cfg_;
  int64_t cost_ = 0;
};

// Tabu min-conflicts search with k colours. Cost = violated knot pairs + equal-colour link
// pairs at a knot (when adjacent_distinct). The fast path for D = 1 and radius 0 counts knots
// per code in a hash map; otherwise partner lists are scanned.
class LocalSearch : public CostModel {
 public:
  LocalSearch(const Net& net, const ColoringOptions& o, int k, uint64_t seed)
      : CostModel(net, o, k, seed), hashed_(o.min_distance == 1 && o.radius == 0) {}

  bool Run(Budget& budget, std::vector<int>* out) {
    // The border first pays where a distance is asked of the whole net (see SearchBorderFirst).
    const bool border_first = !hashed_ && o_.min_distance >= 2 && o_.radius == 0;
    // Rebuild the list of knots in conflict (a pass over the net) every move while that costs
    // no more than a move, else about as often as it costs what the moves between cost.
    const int64_t refresh = std::max<int64_t>(1, net_.n / (4 * k_ * EvalWork()));
    return SearchBorderFirst(net_, k_, *this, rng_, budget, refresh, border_first, out);
  }
  // An evaluation is four codes hashed (hashed), or a scan of two knots' partners twice: units
  // of roughly equal time (50-70 ns here).
  int64_t EvalWork() const {
    if (hashed_) return 4;
    return 16 + 4 * (net_.n > 0 ? net_.partner_begin[net_.n] / net_.n : 0);
  }
  int64_t ScanWork() const { return 1; }

  // Sets the colouring, which knots count and which links may change; recounts the cost.
  // False when the budget ran out first (the pair count, n x partners, is charged to it).
  bool Start(std::vector<int> colour, std::vector<char> active, std::vector<char> movable,
             Budget& budget) {
    Reset(std::move(colour), std::move(active), std::move(movable));
    pair_conf_.assign(net_.n, 0);
    count_.clear();
    if (hashed_) {
      for (int x = 0; x < net_.n; ++x)
        if (active_[x]) cost_ += count_[CodeKey(o_.rule, cfg_[x])]++;
    } else {
      for (int x = 0; x < net_.n; ++x) {
        if (!budget.Spend(1 + static_cast<int64_t>(net_.partners(x).size()))) return false;
        for (int w : net_.partners(x))
          if (Counted(x, w) && Violates(cfg_[x], cfg_[w])) {
            ++pair_conf_[x];
            if (w > x) ++cost_;
          }
      }
    }
    if (o_.adjacent_distinct)
      for (int x = 0; x < net_.n; ++x)
        if (active_[x]) cost_ += AdjacentPairs(cfg_[x]);
    return true;
  }
  bool Counted(int x, int w) const { return active_[x] && active_[w]; }
  bool Violates(const Cfg& a, const Cfg& b) const {
    return Distance(o_.rule, a, b) < o_.min_distance;
  }
  bool Conflicted(int x) const {
    if (!active_[x]) return false;
    if (o_.adjacent_distinct && AdjacentPairs(cfg_[x]) > 0) return true;
    if (hashed_) return count_.at(CodeKey(o_.rule, cfg_[x])) > 1;
    return pair_conf_[x] > 0;
  }
  // Cost of the pairs touching u or v when their configurations are cu, cv.
  int64_t Contribution(int u, int v, const Cfg& cu, const Cfg& cv) const {
    int64_t s = 0;
    for (int w : net_.partners(u))
      if (Counted(u, w)) s += Violates(cu, w == v ? cv : cfg_[w]);
    for (int w : net_.partners(v))
      if (w != u && Counted(v, w)) s += Violates(cv, cfg_[w]);
    if (o_.adjacent_distinct) s += active_[u] * AdjacentPairs(cu) + active_[v] * AdjacentPairs(cv);
    return s;
  }
  // Change of sum_codes C(count, 2) when one knot moves from code a to code b.
  int64_t MoveCount(uint64_t a, uint64_t b) {
    if (a == b) return 0;
    int64_t d = -(--count_[a]);
    d += count_[b]++;
    return d;
  }
  int64_t Delta(int e, int c) {
    const int u = net_.link_knots[e][0], v = net_.link_knots[e][1];
    const auto [cu, cv] = MovedCfgs(net_, cfg_, e, c);
    if (hashed_) {
      const uint64_t ou = CodeKey(o_.rule, cfg_[u]), ov = CodeKey(o_.rule, cfg_[v]);
      const uint64_t nu = CodeKey(o_.rule, cu), nv = CodeKey(o_.rule, cv);
      // (The hashed path runs with every knot active.)
      int64_t d = MoveCount(ou, nu) + MoveCount(ov, nv);
      MoveCount(nv, ov);
      MoveCount(nu, ou);
      if (o_.adjacent_distinct)
        d +=
            AdjacentPairs(cu) + AdjacentPairs(cv) - AdjacentPairs(cfg_[u]) - AdjacentPairs(cfg_[v]);
      return d;
    }
    return Contribution(u, v, cu, cv) - Contribution(u, v, cfg_[u], cfg_[v]);
  }
  void Apply(int e, int c) {
    const int u = net_.link_knots[e][0], v = net_.link_knots[e][1];
    cost_ += Delta(e, c);
    const Cfg old_u = cfg_[u], old_v = cfg_[v];
    colour_[e] = c;
    cfg_[u] = KnotCfg(net_, colour_, u);
    cfg_[v] = KnotCfg(net_, colour_, v);
    if (hashed_) {
      MoveCount(CodeKey(o_.rule, old_u), CodeKey(o_.rule, cfg_[u]));
      MoveCount(CodeKey(o_.rule, old_v), CodeKey(o_.rule, cfg_[v]));
      return;
    }
    // Update the per-knot pair conflict counts of every pair touching u or v.
    auto update = [&](int x, int w, bool before, bool after) {
      if (before == after) return;
      const int s = after ? 1 : -1;
      pair_conf_[x] += s;
      pair_conf_[w] += s;
    };
    for (int w : net_.partners(u))
      if (Counted(u, w))
        update(u, w, Violates(old_u, w == v ? old_v : cfg_[w]), Violates(cfg_[u], cfg_[w]));
    for (int w : net_.partners(v))
      if (w != u && Counted(v, w))
        update(v, w, Violates(old_v, cfg_[w]), Violates(cfg_[v], cfg_[w]));
  }

  bool hashed_;
  std::vector<int> pair_conf_;
  std::unordered_map<uint64_t, int> count_;
};

// Keys for distance 2 (LocalSearchD2). A key is a family tag (top byte) over a code-like body
// (degree and colours, CodeKey's layout); two knots conflict when a key of one meets a key of a
// MATCHING family with the same body in the other.
//   Multiset and cyclic, one family kWild matching itself: the code with one link colour
//   wildcarded. Two knots of equal degree are within one change of each other exactly when
//   they share such a key (wildcard the link where they differ, or any link when equal).
//   Set: with S = set(a), T = set(b), one change turns a into a configuration with set T
//   exactly when T = S (kOwn meets kOwn), or T = S - x for a colour x on one link of a only
//   (kOwn of b meets kDown of a), or T - y is such an S - x, or T - y = S where a repeats a
//   colour (kSub of b, every T - y, meets kStep of a, the S - x and S-if-repeated). The
//   pair conflicts when this holds in either direction.
enum Family : uint64_t { kWild = 0, kOwn = 1, kDown = 2, kStep = 3, kSub = 4 };
uint64_t Tagged(Family f, uint64_t body) { return (uint64_t{f} << 56) | body; }
Family FamilyOf(uint64_t key) { return static_cast<Family>(key >> 56); }
uint64_t Body(uint64_t key) { return key & ((uint64_t{1} << 56) - 1); }
// The families a key of family f meets.
int Partners(Family f, std::array<Family, 2>* out) {
  switch (f) {
    case kWild: (*out)[0] = kWild; return 1;
    case kOwn: (*out)[0] = kOwn, (*out)[1] = kDown; return 2;
    case kDown: (*out)[0] = kOwn; return 1;
    case kStep: (*out)[0] = kSub; return 1;
    case kSub: (*out)[0] = kStep; return 1;
  }
  return 0;
}
// Body of a set of colours for a knot of degree d.
uint64_t SetBody(int d, const std::vector<int>& colours) {
  Cfg y;
  y.d = static_cast<int>(colours.size());
  for (int i = 0; i < y.d; ++i) y.c[i] = colours[i];
  uint64_t key = static_cast<uint64_t>(d);
  for (int i = 0; i < 4; ++i) key = (key << 8) | static_cast<uint64_t>(y.c[i] + 1);
  return key;
}
void DistanceTwoKeys(CodeRule rule, const Cfg& x, std::vector<uint64_t>* keys) {
  keys->clear();
  if (rule != CodeRule::kSet) {
    for (int i = 0; i < x.d; ++i) {
      Cfg y = x;
      y.c[i] = kWildColour;
      keys->push_back(Tagged(kWild, CodeKey(rule, y)));
    }
  } else {
    std::array<int, 4> c = x.c;
    std::sort(c.begin(), c.begin() + x.d);
    std::vector<int> set, single;
    for (int i = 0; i < x.d; ++i) {
      if (i > 0 && c[i] == c[i - 1]) continue;
      set.push_back(c[i]);
      const bool once = (i + 1 == x.d || c[i + 1] != c[i]);
      if (once) single.push_back(c[i]);
    }
    keys->push_back(Tagged(kOwn, SetBody(x.d, set)));
    if (set.size() < static_cast<size_t>(x.d)) keys->push_back(Tagged(kStep, SetBody(x.d, set)));
    for (size_t j = 0; j < set.size(); ++j) {  // (S - x empty only on one-link knots)
      std::vector<int> less = set;
      less.erase(less.begin() + static_cast<long>(j));
      const uint64_t body = SetBody(x.d, less);
      keys->push_back(Tagged(kSub, body));
      if (std::find(single.begin(), single.end(), set[j]) != single.end()) {
        keys->push_back(Tagged(kDown, body));
        keys->push_back(Tagged(kStep, body));
      }
    }
  }
  std::sort(keys->begin(), keys->end());
  keys->erase(std::unique(keys->begin(), keys->end()), keys->end());
}

// Tabu search for min_distance 2 over the whole net (radius 0), every rule, with hashed
// bookkeeping: each knot has a few keys (DistanceTwoKeys), two knots of one degree are within one
// link change of each other exactly when keys of matching families meet, so the cost (meetings of
// keys) is 0 exactly for a valid colouring, and a move (two knots change) costs O(d) hash
// operations instead of a comparison with every knot.
class LocalSearchD2 : public CostModel {
 public:
  LocalSearchD2(const Net& net, const ColoringOptions& o, int k, uint64_t seed)
      : CostModel(net, o, k, seed) {}

  bool Run(Budget& budget, std::vector<int>* out) {
    return SearchBorderFirst(net_, k_, *this, rng_, budget, RefreshEvery(net_), true, out);
  }
  // An evaluation takes four knots' keys out and in (up to 14 keys each under the set rule).
  int64_t EvalWork() const { return o_.rule == CodeRule::kSet ? 32 : 16; }
  int64_t ScanWork() const { return o_.rule == CodeRule::kSet ? 8 : 4; }

  // Sets the colouring, which knots count and which links may change; recounts the keys.
  // False when the budget ran out first (the pair count, n x partners, is charged to it).
  bool Start(std::vector<int> colour, std::vector<char> active, std::vector<char> movable,
             Budget& budget) {
    Reset(std::move(colour), std::move(active), std::move(movable));
    own_.clear();
    own_.reserve(static_cast<size_t>(net_.n) * 4);
    for (int x = 0; x < net_.n; ++x) {
      if (!active_[x]) continue;
      Add(cfg_[x], 1);
      if (o_.adjacent_distinct) cost_ += AdjacentPairs(cfg_[x]);
    }
    budget.work -= int64_t{net_.n} * ScanWork();
    return true;
  }
  // Meetings of `keys` with the keys present (not counting `keys` themselves).
  int64_t Meetings(const std::vector<uint64_t>& keys) const {
    int64_t m = 0;
    std::array<Family, 2> partners;
    for (uint64_t key : keys) {
      const int n = Partners(FamilyOf(key), &partners);
      for (int i = 0; i < n; ++i) {
        const auto it = own_.find(Tagged(partners[i], Body(key)));
        if (it != own_.end()) m += it->second;
      }
    }
    return m;
  }
  // Adds (s = 1) or removes (s = -1) a knot with configuration x, keeping cost_ exact: the
  // cost counts every meeting of two knots' keys once.
  void Add(const Cfg& x, int s) {
    DistanceTwoKeys(o_.rule, x, &scratch_);
    if (s > 0) {
      cost_ += Meetings(scratch_);
      for (uint64_t key : scratch_) ++own_[key];
    } else {
      for (uint64_t key : scratch_) {
        const auto it = own_.find(key);
        if (--it->second == 0) own_.erase(it);
      }
      cost_ -= Meetings(scratch_);
    }
  }
  bool Conflicted(int x) {
    if (!active_[x]) return false;
    const Cfg& cx = cfg_[x];
    if (o_.adjacent_distinct && AdjacentPairs(cx) > 0) return true;
    // Meetings with other knots: x's own keys taken out of the counts.
    DistanceTwoKeys(o_.rule, cx, &scratch_);
    int64_t self = 0;
    std::array<Family, 2> partners;
    for (uint64_t key : scratch_) {
      const int n = Partners(FamilyOf(key), &partners);
      for (int i = 0; i < n; ++i)
        self +=
            std::binary_search(scratch_.begin(), scratch_.end(), Tagged(partners[i], Body(key)));
    }
    return Meetings(scratch_) > self;
  }
  // Knots u, v (the ends of one link) from configurations fu, fv to tu, tv: key counts and
  // cost_ updated; returns the cost change.
  int64_t Shift(int u, int v, const Cfg& fu, const Cfg& fv, const Cfg& tu, const Cfg& tv) {
    const int64_t before = cost_;
    if (active_[u]) Add(fu, -1);
    if (active_[v]) Add(fv, -1);
    if (active_[u]) Add(tu, 1);
    if (active_[v]) Add(tv, 1);
    if (o_.adjacent_distinct) {
      if (active_[u]) cost_ += AdjacentPairs(tu) - AdjacentPairs(fu);
      if (active_[v]) cost_ += AdjacentPairs(tv) - AdjacentPairs(fv);
    }
    return cost_ - before;
  }
  int64_t Delta(int e, int c) {
    const int u = net_.link_knots[e][0], v = net_.link_knots[e][1];
    const auto [cu, cv] = MovedCfgs(net_, cfg_, e, c);
    const int64_t d = Shift(u, v, cfg_[u], cfg_[v], cu, cv);
    Shift(u, v, cu, cv, cfg_[u], cfg_[v]);
    return d;
  }
  void Apply(int e, int c) {
    const int u = net_.link_knots[e][0], v = net_.link_knots[e][1];
    const auto [cu, cv] = MovedCfgs(net_, cfg_, e, c);
    Shift(u, v, cfg_[u], cfg_[v], cu, cv);
    colour_[e] = c;
    cfg_[u] = cu;
    cfg_[v] = cv;
  }

  std::unordered_map<uint64_t, int> own_;  // key -> active knots having it
  std::vector<uint64_t> scratch_;
};

// Backtracking over links in knot order (each knot's right then down link, row-major), so a
// knot is complete as soon as its own right and down links are set. Colours are introduced in
// increasing order (colour permutations preserve every rule). Checks: adjacency as each link is
// set, distance to every earlier-completed partner as each knot completes.
class ExactSearch {
 public:
  ExactSearch(const Net& net, const ColoringOptions& o, int k, Budget& budget)
      : net_(net), o_(o), k_(k), budget_(budget) {
    for (int x = 0; x < net.n; ++x)
      for (int i = 0; i < net.degree[x]; ++i) {
        const int e = net.knot_links[x][i];
        if (net.link_knots[e][0] == x) order_.push_back(e);  // x's right / down links
      }
    std::vector<int> pos(net.links);
    for (int i = 0; i < net.links; ++i) pos[order_[i]] = i;
    completes_.resize(net.links);
    complete_step_.assign(net.n, -1);
    for (int x = 0; x < net.n; ++x) {
      int last = -1;
      for (int i = 0; i < net.degree[x]; ++i) last = std::max(last, pos[net.knot_links[x][i]]);
      complete_step_[x] = last;
      if (last >= 0) completes_[last].push_back(x);
    }
    colour_.assign(net.links, -1);
  }

  // 1 found, 0 infeasible, -1 time up.
  int Run(std::vector<int>* out) {
    const int r = Dfs(0, -1);
    if (r == 1) *out = colour_;
    return r;
  }

 private:
  int Dfs(int step, int max_used) {
    if (step == net_.links) return 1;
    if (!budget_.Spend(1 + checks_)) return -1;
    checks_ = 0;
    const int e = order_[step];
    const int top = std::min(k_ - 1, max_used + 1);
    for (int c = 0; c <= top; ++c) {
      colour_[e] = c;
      if (!Consistent(e, step)) continue;
      const int r = Dfs(step + 1, std::max(max_used, c));
      if (r != 0) return r;
    }
    colour_[e] = -1;
    return 0;
  }
  bool Consistent(int e, int step) const {
    if (o_.adjacent_distinct)
      for (int x : net_.link_knots[e])
        for (int i = 0; i < net_.degree[x]; ++i) {
          const int f = net_.knot_links[x][i];
          if (f != e && colour_[f] == colour_[e]) return false;
        }
    for (int x : completes_[step]) {
      const Cfg cx = KnotCfg(net_, colour_, x);
      for (int w : net_.partners(x)) {
        const int sw = complete_step_[w];
        if (sw > step || (sw == step && w > x)) continue;
        ++checks_;
        if (Distance(o_.rule, cx, KnotCfg(net_, colour_, w)) < o_.min_distance) return false;
      }
    }
    return true;
  }

  const Net& net_;
  const ColoringOptions& o_;
  int k_;
  Budget& budget_;              // in nodes and code comparisons
  mutable int64_t checks_ = 0;  // code comparisons since the last node
  std::vector<int> order_;
  std::vector<std::vector<int>> completes_;
  std::vector<int> complete_step_;
  std::vector<int> colour_;
};

}  // namespace

bool DistanceTwoKeysMeet(CodeRule rule, const std::vector<int>& a, const std::vector<int>& b) {
  std::vector<uint64_t> ka, kb;
  DistanceTwoKeys(rule, ToCfg(a), &ka);
  DistanceTwoKeys(rule, ToCfg(b), &kb);
  std::array<Family, 2> partners;
  for (uint64_t key : ka) {
    const int n = Partners(FamilyOf(key), &partners);
    for (int i = 0; i < n; ++i)
      if (std::binary_search(kb.begin(), kb.end(), Tagged(partners[i], Body(key)))) return true;
  }
  return false;
}

bool ParseCodeRule(const std::string& name, CodeRule* rule) {
  if (name == "set")
    *rule = CodeRule::kSet;
  else if (name == "multiset")
    *rule = CodeRule::kMultiset;
  else if (name == "cyclic")
    *rule = CodeRule::kCyclic;
  else
    return false;
  return true;
}

std::string CodeRuleName(CodeRule rule) {
  switch (rule) {
    case CodeRule::kSet: return "set";
    case CodeRule::kMultiset: return "multiset";
    case CodeRule::kCyclic: return "cyclic";
  }
  return "?";
}

bool ColoringOptions::IsValid(std::string* error) const {
  std::string e;
  if (min_distance < 1)
    e = "min_distance must be >= 1";
  else if (radius < 0)
    e = "radius must be >= 0 (0: whole net)";
  else if (max_colors < 1 || max_colors > 64)
    e = "max_colors must be in 1..64";
  else if (!(time_limit_s >= 0.0))
    e = "time_limit_s must be >= 0";
  else if (work_per_link < 1)
    e = "work_per_link must be >= 1";
  else if (exact_work < 0)
    e = "exact_work must be >= 0";
  if (error) *error = e;
  return e.empty();
}

int NumLinks(int rows, int cols) {
  if (rows <= 0 || cols <= 0) return 0;
  return rows * (cols - 1) + (rows - 1) * cols;
}

std::array<int, 4> LinkKnots(int rows, int cols, int link) {
  const int horizontal = rows * (cols - 1);
  if (link < horizontal) {
    const int r = link / (cols - 1), c = link % (cols - 1);
    return {r, c, r, c + 1};
  }
  const int l = link - horizontal;
  const int r = l / cols, c = l % cols;
  return {r, c, r + 1, c};
}

std::vector<int> KnotLinks(int rows, int cols, int r, int c) {
  const int horizontal = rows * (cols - 1);
  std::vector<int> l;
  if (c + 1 < cols) l.push_back(r * (cols - 1) + c);         // right
  if (r + 1 < rows) l.push_back(horizontal + r * cols + c);  // down
  if (c > 0) l.push_back(r * (cols - 1) + c - 1);            // left
  if (r > 0) l.push_back(horizontal + (r - 1) * cols + c);   // up
  return l;
}

std::vector<int> KnotLinkColours(const NetColoring& coloring, int r, int c) {
  std::vector<int> out;
  for (int l : KnotLinks(coloring.rows, coloring.cols, r, c))
    out.push_back(coloring.link_colour.at(l));
  return out;
}

std::vector<int> KnotCode(CodeRule rule, const std::vector<int>& colours) {
  const Cfg y = Canonical(rule, ToCfg(colours));
  return std::vector<int>(y.c.begin(), y.c.begin() + y.d);
}

std::string CodeString(CodeRule rule, const std::vector<int>& code) {
  std::string s = rule == CodeRule::kCyclic ? "(" : "{";
  for (size_t i = 0; i < code.size(); ++i) {
    if (i > 0) s += ',';
    s += std::to_string(code[i]);
  }
  return s + (rule == CodeRule::kCyclic ? ")" : "}");
}

int KnotDistance(CodeRule rule, const std::vector<int>& a, const std::vector<int>& b) {
  return Distance(rule, ToCfg(a), ToCfg(b));
}

int64_t CountCodes(CodeRule rule, int degree, int k, bool adjacent_distinct) {
  if (degree == 0) return 1;
  if (adjacent_distinct) {
    const int64_t subsets = Binomial(k, degree);
    return (rule == CodeRule::kCyclic && degree == 4) ? 3 * subsets : subsets;  // 4!/8 = 3
  }
  switch (rule) {
    case CodeRule::kSet: {
      int64_t s = 0;
      for (int j = 1; j <= std::min(degree, k); ++j) s += Binomial(k, j);
      return s;
    }
    case CodeRule::kMultiset: return Binomial(k + degree - 1, degree);
    case CodeRule::kCyclic:
      if (degree <= 3) return Binomial(k + degree - 1, degree);
      {
        const int64_t kk = k;  // bracelets of length 4
        return (kk * kk * kk * kk + 2 * kk * kk * kk + 3 * kk * kk + 2 * kk) / 8;
      }
  }
  return 0;
}

int64_t MaxCodePacking(CodeRule rule, int degree, int k, bool adjacent_distinct, int min_distance) {
  const int64_t all = CountCodes(rule, degree, k, adjacent_distinct);
  if (min_distance <= 1 || k <= 0) return all;
  if (min_distance > degree) return std::min<int64_t>(all, 1);  // any two are within degree
  // The set distance is never larger than the multiset distance (a configuration of the other
  // knot's multiset has its set), so knots pairwise D apart as sets are so as multisets too.
  const CodeRule keyed = rule == CodeRule::kSet ? CodeRule::kMultiset : rule;
  return std::min(all, PatternPackingBound(keyed, degree, k, adjacent_distinct, min_distance));
}

namespace {

// The most knots with in(r, c) in one box [u0, u0 + R] x [v0, v0 + R] of the rotated coordinates
// u = r + c, v = r - c + cols - 1 (each in 0 .. rows + cols - 2).
template <typename In>
int LargestInBox(int rows, int cols, int R, In in) {
  const int w = rows + cols - 1;
  // sum[u][v]: knots with in() at u' < u, v' < v.
  std::vector<int> sum(static_cast<size_t>(w + 1) * (w + 1), 0);
  auto at = [&](int u, int v) -> int& { return sum[static_cast<size_t>(u) * (w + 1) + v]; };
  for (int r = 0; r < rows; ++r)
    for (int c = 0; c < cols; ++c)
      if (in(r, c)) ++at(r + c + 1, r - c + cols);
  for (int u = 1; u <= w; ++u)
    for (int v = 1; v <= w; ++v) at(u, v) += at(u - 1, v) + at(u, v - 1) - at(u - 1, v - 1);
  int best = 0;
  for (int u0 = -R; u0 < w; ++u0)
    for (int v0 = -R; v0 < w; ++v0) {
      const int u1 = std::clamp(u0, 0, w), u2 = std::clamp(u0 + R + 1, 0, w);
      const int v1 = std::clamp(v0, 0, w), v2 = std::clamp(v0 + R + 1, 0, w);
      best = std::max(best, at(u2, v2) - at(u1, v2) - at(u2, v1) + at(u1, v1));
    }
  return best;
}

}  // namespace

int ColoringLowerBound(int rows, int cols, const ColoringOptions& options) {
  if (NumLinks(rows, cols) == 0) return 0;
  // Largest group per degree that must pairwise differ.
  std::array<int, 5> need{};
  auto degree_of = [&](int r, int c) {
    return (r > 0) + (r + 1 < rows) + (c > 0) + (c + 1 < cols);
  };
  const int R = options.radius;
  if (R == 0 || R >= rows + cols) {
    for (int r = 0; r < rows; ++r)
      for (int c = 0; c < cols; ++c) ++need[degree_of(r, c)];
  } else {
    // Graph distance is |dr| + |dc| = max(|du|, |dv|) with u = r + c, v = r - c, so a group of
    // pairwise distance <= R fits in a box [u0, u0 + R] x [v0, v0 + R]: the largest count of
    // each degree over all such boxes, from prefix sums over (u, v) (O((rows + cols)^2) per
    // degree instead of R^2 per box).
    for (int d = 1; d < 5; ++d)
      need[d] = LargestInBox(rows, cols, R, [&](int r, int c) { return degree_of(r, c) == d; });
  }
  // Two knots of equal degree d joined by a link share its colour, so they are at most d - 1
  // apart under every rule: min_distance >= d makes such a pair impossible to separate.
  for (int r = 0; r < rows; ++r)
    for (int c = 0; c < cols; ++c) {
      const int d = degree_of(r, c);
      if (options.min_distance < d) continue;
      if ((c + 1 < cols && degree_of(r, c + 1) == d) || (r + 1 < rows && degree_of(r + 1, c) == d))
        return 65;
    }
  int max_degree = 0;
  for (int d = 0; d < 5; ++d)
    if (need[d] > 0) max_degree = d;
  for (int k = options.adjacent_distinct ? max_degree : 1; k <= 64; ++k) {
    bool ok = true;
    for (int d = 1; d < 5 && ok; ++d)
      if (need[d] > 1)
        ok = MaxCodePacking(options.rule, d, k, options.adjacent_distinct, options.min_distance) >=
             need[d];
    if (ok) return k;
  }
  return 65;  // no palette of <= 64 colours can work
}

double EstimateColoringBytes(int rows, int cols, const ColoringOptions& o) {
  const double n = static_cast<double>(rows) * cols, links = NumLinks(rows, cols);
  const double hash_entry = 48;  // an unordered_map node with its bucket, as glibc allocates it
  // The net (links per knot, degrees, knots per link) and the partner lists where read.
  double bytes = 28 * n + 8 * links;
  if (HeuristicNeedsPartners(o) || RunsExactStage(rows, cols))
    bytes += 8 * n + 4 * n * static_cast<double>(PartnersPerKnot(rows, cols, o.radius));
  // The heuristic: tabu tenures for every link and colour, the colouring and its copies,
  // per-knot configurations, masks and conflict lists.
  bytes += 4 * links * o.max_colors + 30 * links + 50 * n;
  // Its code counts (distance 1) or keys (distance 2: up to 14 per knot under the set rule).
  const bool hashed = o.radius == 0 && o.min_distance <= 2;
  const double keys = o.min_distance == 1 ? 1 : o.rule == CodeRule::kSet ? 14 : 4;
  if (hashed) bytes += hash_entry * n * keys;
  // The lower bound's prefix sums over the rotated grid.
  if (o.radius > 0) bytes += 4.0 * (rows + cols) * (rows + cols);
  // VerifyColoring (colours and codes per knot, the table of codes) and the file's text, held
  // twice while written (about 47 characters a link).
  bytes += (2 * 56 + 16 + hash_entry) * n + 2 * 47 * links;
  return bytes;
}

namespace {

Clock::time_point After(Clock::time_point t0, double seconds) {
  return t0 + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(seconds));
}

// The exact search with k colours on a net built with its partner lists.
int ExactOnNet(const Net& net, const ColoringOptions& o, int k, Budget& budget,
               std::vector<int>* link_colour) {
  if (net.links == 0) {
    link_colour->clear();
    return 1;
  }
  if (k <= 0) return 0;
  ExactSearch search(net, o, k, budget);
  return search.Run(link_colour);
}

// The heuristic's work for one palette: work_per_link per link, at least a million units (small
// nets are cheap, and a few thousand moves decide little).
int64_t WorkBudget(int links, const ColoringOptions& o) {
  return std::max<int64_t>(1'000'000, o.work_per_link * links);
}

}  // namespace

int ExactColoring(int rows, int cols, const ColoringOptions& options, int k, double time_limit_s,
                  std::vector<int>* link_colour) {
  if (!RunsExactStage(rows, cols))
    throw std::invalid_argument("ExactColoring: more than " + std::to_string(kExactSearchMaxKnots) +
                                " knots");
  const Net net = BuildNet(rows, cols, options, true);
  Budget budget{options.exact_work, After(Clock::now(), time_limit_s)};
  return ExactOnNet(net, options, k, budget, link_colour);
}

NetColoring SolveColoring(int rows, int cols, const ColoringOptions& options) {
  const auto t0 = Clock::now();
  std::string error;
  if (!options.IsValid(&error)) throw std::invalid_argument("ColoringOptions: " + error);
  if (rows < 1 || cols < 1)
    throw std::invalid_argument("SolveColoring: rows and cols must be >= 1");
  NetColoring result;
  result.rows = rows;
  result.cols = cols;
  result.options = options;
  result.lower_bound = ColoringLowerBound(rows, cols, options);
  if (NumLinks(rows, cols) == 0) {
    result.method = "exact";
    result.optimal = true;
    result.wall_s = Since(t0);
    return result;
  }
  // Before anything is allocated: no palette of max_colors colours can work (see the bound).
  if (result.lower_bound > options.max_colors) {
    result.method = "infeasible";
    result.wall_s = Since(t0);
    return result;
  }
  const bool exact_stage = RunsExactStage(rows, cols);
  result.exact_skipped = !exact_stage;
  const Net net = BuildNet(rows, cols, options, HeuristicNeedsPartners(options) || exact_stage);
  const auto deadline = After(t0, options.time_limit_s);
  // True (and the result marked) once the wall-clock cap has passed.
  auto out_of_time = [&] {
    const bool past = Clock::now() > deadline;
    result.time_limited = result.time_limited || past;
    return past;
  };
  result.method = "none";
  // Each palette within its work, and within a share of the time limit so that a short limit is
  // not spent on the first palette (a share that cuts the work short marks the result too).
  auto try_heuristic = [&](int k, int64_t work, double seconds) {
    Budget budget{work, std::min(deadline, After(Clock::now(), seconds))};
    std::vector<int> colour;
    const uint64_t seed = options.seed + static_cast<uint64_t>(k);
    bool found;
    if (options.min_distance == 2 && options.radius == 0) {
      LocalSearchD2 search(net, options, k, seed);
      found = search.Run(budget, &colour);
    } else {
      LocalSearch search(net, options, k, seed);
      found = search.Run(budget, &colour);
    }
    result.time_limited = result.time_limited || budget.capped;
    if (!found) return false;
    result.colors = k;
    result.link_colour = std::move(colour);
    result.method = "heuristic";
    return true;
  };
  // Heuristic: upwards from the lower bound with one budget per palette (and 5 % of the time
  // limit) until a palette works (steps of 1, 1, 2, 4, ... so that a weak bound, D >= 2, is left
  // behind quickly; the largest palette gets 4 budgets and all the time left), bisect between the
  // last failure and the palette found (a share of the time left per round), then downwards with
  // 4 budgets (and half the time left) each while it keeps working.
  const int64_t work = WorkBudget(net.links, options);
  auto left = [&] { return options.time_limit_s - Since(t0); };
  int failed_below = result.lower_bound - 1;  // the largest palette that failed so far
  for (int k = result.lower_bound, step = 1; k <= options.max_colors + step - 1;
       k += step, step *= (k > result.lower_bound + 1 ? 2 : 1)) {
    const int kk = std::min(k, options.max_colors);
    if (out_of_time()) break;
    const bool last = kk == options.max_colors;
    if (try_heuristic(kk, last ? 4 * work : work, last ? left() : 0.05 * options.time_limit_s))
      break;
    failed_below = kk;
    if (kk == options.max_colors) break;
  }
  while (result.colors > 0 && result.colors - failed_below > 1 && !out_of_time()) {
    int rounds = 1;
    for (int gap = result.colors - failed_below; gap > 1; gap = (gap + 1) / 2) ++rounds;
    const int mid = failed_below + (result.colors - failed_below) / 2;
    if (!try_heuristic(mid, work, left() / rounds)) failed_below = mid;
  }
  for (int k = result.colors - 1; result.colors > 0 && k >= result.lower_bound; --k)
    if (out_of_time() || !try_heuristic(k, 4 * work, 0.5 * left())) break;
  if (result.method == "none") {
    result.wall_s = Since(t0);
    return result;
  }
  // Prove (or improve) with the exact search on colors - 1, within one work budget.
  result.optimal = result.colors <= result.lower_bound;
  Budget exact_budget{options.exact_work, deadline};
  while (exact_stage && !result.optimal && !out_of_time()) {
    std::vector<int> colour;
    const int r = ExactOnNet(net, options, result.colors - 1, exact_budget, &colour);
    result.time_limited = result.time_limited || exact_budget.capped;
    if (r < 0) break;
    result.method = "heuristic+exact";
    if (r == 0) {
      result.optimal = true;
    } else {
      result.colors -= 1;
      result.link_colour = colour;
      result.optimal = result.colors <= result.lower_bound;
    }
  }
  result.wall_s = Since(t0);
  return result;
}

namespace {

// Knots in the diamond of radius R around a knot (all of them for radius 0).
double DiamondSize(int rows, int cols, int radius) {
  const double n = static_cast<double>(rows) * cols, r = radius;
  return radius == 0 ? n : std::min(n, 2 * r * r + 2 * r + 1);
}

// Configurations of d links within `changes` link changes of one configuration, k colours.
double HammingBallSize(int d, int k, int changes) {
  double size = 0, choose = 1, power = 1;
  for (int j = 0; j <= std::min(changes, d); ++j) {
    size += choose * power;
    choose = choose * (d - j) / (j + 1);
    power *= std::max(k - 1, 0);
  }
  return size;
}

// The first non-empty compare(x, w) over the knots x and the knots w > x in the diamond of
// `radius` around x (row-major order; radius 0: every knot).
template <typename Compare>
std::string FirstViolationWithin(int rows, int cols, int radius, Compare compare) {
  const int reach = radius == 0 ? rows + cols : radius;
  for (int x = 0; x < rows * cols; ++x) {
    const int r = x / cols, c = x % cols;
    for (int wr = r; wr <= std::min(rows - 1, r + reach); ++wr) {
      const int span = reach - (wr - r);
      for (int wc = std::max(0, c - span); wc <= std::min(cols - 1, c + span); ++wc) {
        const int w = wr * cols + wc;
        if (w <= x) continue;
        const std::string violation = compare(x, w);
        if (!violation.empty()) return violation;
      }
    }
  }
  return "";
}

// A knot code and its degree as one number (codes hold at most 4 colours below 64).
uint64_t PackedCode(size_t degree, const std::vector<int>& code) {
  uint64_t key = degree;
  for (int c : code) key = key * 65 + static_cast<uint64_t>(c + 1);
  return key;
}

// The first non-empty compare(x, w) for knots w whose code some configuration within
// min_distance - 1 link changes of knot x has (x in order; a table of codes, O(n) memory).
template <typename Compare>
std::string FirstViolationByCode(const ColoringOptions& o,
                                 const std::vector<std::vector<int>>& colours, int k,
                                 Compare compare) {
  const int n = static_cast<int>(colours.size());
  std::unordered_multimap<uint64_t, int> knots_of;
  knots_of.reserve(n);
  for (int x = 0; x < n; ++x)
    knots_of.emplace(PackedCode(colours[x].size(), KnotCode(o.rule, colours[x])), x);
  std::string violation;
  std::vector<int> y;
  // Changes links from `from` on with `left` changes to spare; true when a violation was found.
  std::function<bool(int, size_t, int)> visit = [&](int x, size_t from, int left) {
    const auto [begin, end] = knots_of.equal_range(PackedCode(y.size(), KnotCode(o.rule, y)));
    for (auto it = begin; it != end; ++it)
      if (!(violation = compare(x, it->second)).empty()) return true;
    if (left == 0) return false;
    for (size_t i = from; i < y.size(); ++i) {
      const int own = y[i];
      for (int c = 0; c < k; ++c) {
        if (c == own) continue;
        y[i] = c;
        if (visit(x, i + 1, left - 1)) return true;
      }
      y[i] = own;
    }
    return false;
  };
  for (int x = 0; x < n; ++x) {
    y = colours[x];
    if (visit(x, 0, o.min_distance - 1)) return violation;
  }
  return "";
}

}  // namespace

bool VerifyColoring(const NetColoring& col, std::string* why) {
  auto fail = [&](const std::string& m) {
    if (why) *why = m;
    return false;
  };
  const ColoringOptions& o = col.options;
  std::string error;
  if (!o.IsValid(&error)) return fail(error);
  if (col.rows < 1 || col.cols < 1) return fail("rows and cols must be >= 1");
  const int links = NumLinks(col.rows, col.cols);
  if (static_cast<int>(col.link_colour.size()) != links)
    return fail("expected " + std::to_string(links) + " link colours, got " +
                std::to_string(col.link_colour.size()));
  for (int l = 0; l < links; ++l)
    if (col.link_colour[l] < 0 || col.link_colour[l] >= col.colors)
      return fail("link " + std::to_string(l) + ": colour " + std::to_string(col.link_colour[l]) +
                  " outside 0.." + std::to_string(col.colors - 1));
  // Each knot's colours gathered by direction from the link list (not via KnotLinks).
  const int n = col.rows * col.cols;
  std::vector<std::array<int, 4>> dir(n, {-1, -1, -1, -1});  // right, down, left, up
  for (int l = 0; l < links; ++l) {
    const auto k = LinkKnots(col.rows, col.cols, l);
    const int a = k[0] * col.cols + k[1], b = k[2] * col.cols + k[3];
    const bool horizontal = k[0] == k[2];
    dir[a][horizontal ? 0 : 1] = col.link_colour[l];
    dir[b][horizontal ? 2 : 3] = col.link_colour[l];
  }
  std::vector<std::vector<int>> colours(n), codes(n);
  auto name = [&](int x) {
    return "knot (" + std::to_string(x / col.cols) + ", " + std::to_string(x % col.cols) + ")";
  };
  for (int x = 0; x < n; ++x) {
    for (int c : dir[x])
      if (c >= 0) colours[x].push_back(c);
    codes[x] = KnotCode(o.rule, colours[x]);
    if (o.adjacent_distinct)
      for (size_t i = 0; i < colours[x].size(); ++i)
        for (size_t j = i + 1; j < colours[x].size(); ++j)
          if (colours[x][i] == colours[x][j])
            return fail(name(x) + ": two links share colour " + std::to_string(colours[x][i]) +
                        " (adjacent_distinct)");
  }
  // The pairs that must differ. On the full grid the graph distance is |dr| + |dc| (a shortest
  // path turns at most once), so no breadth-first search is needed.
  auto hops = [&](int x, int w) {
    return std::abs(x / col.cols - w / col.cols) + std::abs(x % col.cols - w % col.cols);
  };
  // Empty when knots x and w may share their codes' neighbourhood, else the violation.
  auto compare = [&](int x, int w) -> std::string {
    if (x == w || colours[w].size() != colours[x].size()) return "";
    if (o.radius > 0 && hops(x, w) > o.radius) return "";
    const int d = KnotDistance(o.rule, colours[x], colours[w]);
    if (d >= o.min_distance) return "";
    if (w < x) std::swap(x, w);
    return name(x) + " and " + name(w) + " (degree " + std::to_string(colours[x].size()) + ", " +
           std::to_string(hops(x, w)) + " links apart): codes " + CodeString(o.rule, codes[x]) +
           " and " + CodeString(o.rule, codes[w]) + " at distance " + std::to_string(d) +
           " < min_distance " + std::to_string(o.min_distance);
  };
  // Two ways, whichever compares fewer: each knot against the knots within the radius (the
  // diamond around it), or each knot's configurations within min_distance - 1 link changes
  // looked up in a table of codes. The second finds every pair closer than min_distance: such a
  // pair has a knot whose links reach the other's code in fewer than min_distance changes.
  const double pairwise = static_cast<double>(n) * DiamondSize(col.rows, col.cols, o.radius);
  const double looked_up =
      static_cast<double>(n) * HammingBallSize(4, col.colors, o.min_distance - 1);
  // (With a small radius the table would return the knots of a code from all over the net.)
  const bool by_code =
      looked_up < pairwise && (o.radius == 0 || 2 * DiamondSize(col.rows, col.cols, o.radius) >= n);
  const std::string violation = !by_code
                                    ? FirstViolationWithin(col.rows, col.cols, o.radius, compare)
                                    : FirstViolationByCode(o, colours, col.colors, compare);
  if (!violation.empty()) return fail(violation);
  return true;
}

void WriteColoring(const std::string& path, const NetColoring& col,
                   const std::vector<std::array<int, 3>>& palette_srgb) {
  std::ostringstream os;
  const ColoringOptions& o = col.options;
  os << "rows: " << col.rows << "\ncols: " << col.cols << "\nrule: " << CodeRuleName(o.rule)
     << "\nmin_distance: " << o.min_distance << "\nradius: " << o.radius
     << "\nadjacent_distinct: " << (o.adjacent_distinct ? "true" : "false")
     << "\ncolors: " << col.colors << "\nlower_bound: " << col.lower_bound
     << "\noptimal: " << (col.optimal ? "true" : "false") << "\nmethod: \"" << col.method << "\"\n";
  if (!col.palette_names.empty() || !palette_srgb.empty()) {
    os << "palette:\n";
    for (int i = 0; i < col.colors; ++i) {
      // Appended, not "c" + ...: GCC 12 warns of a false -Wrestrict on that once inlined.
      const std::string name = i < static_cast<int>(col.palette_names.size())
                                   ? col.palette_names[i]
                                   : std::string("c").append(std::to_string(i));
      os << "  - {name: \"" << name << "\"";
      if (i < static_cast<int>(palette_srgb.size()))
        os << ", srgb: [" << palette_srgb[i][0] << ", " << palette_srgb[i][1] << ", "
           << palette_srgb[i][2] << "]";
      os << "}\n";
    }
  }
  os << "links:\n";
  for (int l = 0; l < static_cast<int>(col.link_colour.size()); ++l) {
    const auto k = LinkKnots(col.rows, col.cols, l);
    os << "  - {a: [" << k[0] << ", " << k[1] << "], b: [" << k[2] << ", " << k[3]
       << "], colour: " << col.link_colour[l] << "}\n";
  }
  WriteTextFile(path, os.str());
}

NetColoring ReadColoring(const std::string& path, std::vector<std::array<int, 3>>* palette_srgb) {
  YamlMap root(LoadYamlFile(path), path, "");
  root.AllowOnly({"rows", "cols", "rule", "min_distance", "radius", "adjacent_distinct", "colors",
                  "lower_bound", "optimal", "method", "palette", "links"});
  NetColoring col;
  col.rows = root.Int("rows");
  if (col.rows < 1) root.Fail("rows", "must be >= 1");
  col.cols = root.Int("cols");
  if (col.cols < 1) root.Fail("cols", "must be >= 1");
  if (!ParseCodeRule(root.String("rule"), &col.options.rule))
    root.Fail("rule", "expected set, multiset or cyclic");
  col.options.min_distance = root.Int("min_distance", 1);
  if (col.options.min_distance < 1) root.Fail("min_distance", "must be >= 1");
  col.options.radius = root.Int("radius", 0);
  if (col.options.radius < 0) root.Fail("radius", "must be >= 0");
  col.options.adjacent_distinct = root.Bool("adjacent_distinct", false);
  col.colors = root.Int("colors");
  if (col.colors < 0 || col.colors > 64) root.Fail("colors", "must be in 0..64");
  col.lower_bound = root.Int("lower_bound", 0);
  col.optimal = root.Bool("optimal", false);
  col.method = root.String("method", "");
  std::vector<std::array<int, 3>> srgb;
  if (root.Has("palette")) {
    const YAML::Node list = root.Get("palette");
    if (!list.IsSequence()) root.Fail("palette", "expected a list of {name, srgb}");
    if (static_cast<int>(list.size()) != col.colors)
      root.Fail("palette", "expected " + std::to_string(col.colors) + " entries (colors), got " +
                               std::to_string(list.size()));
    for (size_t i = 0; i < list.size(); ++i) {
      YamlMap entry(list[i], path, "palette[" + std::to_string(i) + "]");
      entry.AllowOnly({"name", "srgb"});
      col.palette_names.push_back(entry.String("name"));
      if (entry.Has("srgb")) {
        const std::vector<int> v = entry.Ints("srgb");
        if (v.size() != 3) entry.Fail("srgb", "expected [r, g, b]");
        for (int x : v)
          if (x < 0 || x > 255) entry.Fail("srgb", "components must be in 0..255");
        srgb.push_back({v[0], v[1], v[2]});
      }
    }
    if (!srgb.empty() && srgb.size() != list.size())
      root.Fail("palette", "srgb given for some entries but not all");
  }
  const int links = NumLinks(col.rows, col.cols);
  const YAML::Node list = root.Get("links");
  if (!list.IsSequence()) root.Fail("links", "expected a list of {a, b, colour}");
  if (static_cast<int>(list.size()) != links)
    root.Fail("links", "expected " + std::to_string(links) + " links for a " +
                           std::to_string(col.rows) + " x " + std::to_string(col.cols) +
                           " net, got " + std::to_string(list.size()));
  col.link_colour.assign(links, -1);
  for (size_t i = 0; i < list.size(); ++i) {
    YamlMap entry(list[i], path, "links[" + std::to_string(i) + "]");
    entry.AllowOnly({"a", "b", "colour"});
    const std::vector<int> a = entry.Ints("a"), b = entry.Ints("b");
    if (a.size() != 2) entry.Fail("a", "expected [row, col]");
    if (b.size() != 2) entry.Fail("b", "expected [row, col]");
    // Which link joins a and b (either order).
    int id = -1;
    for (const auto& [p, q] : {std::pair(a, b), std::pair(b, a)}) {
      if (p[0] < 0 || p[0] >= col.rows || p[1] < 0 || p[1] >= col.cols) continue;
      for (int l : KnotLinks(col.rows, col.cols, p[0], p[1])) {
        const auto k = LinkKnots(col.rows, col.cols, l);
        if (k[0] == p[0] && k[1] == p[1] && k[2] == q[0] && k[3] == q[1]) id = l;
      }
    }
    if (id < 0) entry.Fail("b", "knots a and b are not neighbours in the net");
    if (col.link_colour[id] >= 0) entry.Fail("a", "this link is listed twice");
    const int c = entry.Int("colour");
    if (c < 0 || c >= col.colors)
      entry.Fail("colour", "must be in 0.." + std::to_string(col.colors - 1) + " (got " +
                               std::to_string(c) + ")");
    col.link_colour[id] = c;
  }
  std::string why;
  if (!VerifyColoring(col, &why))
    throw InputError(path + ": the colouring breaks its own rule: " + why);
  if (palette_srgb) *palette_srgb = srgb;
  return col;
}

}  // namespace netlab::recon
