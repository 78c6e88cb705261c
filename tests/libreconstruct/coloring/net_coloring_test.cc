#include "libreconstruct/coloring/net_coloring.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <bitset>
#include <cmath>
#include <fstream>
#include <functional>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "common/errors.h"
#include "tests/libreconstruct/test_files.h"

namespace netlab::recon {
namespace {

using testing::ScratchDir;

constexpr CodeRule kRules[] = {CodeRule::kSet, CodeRule::kMultiset, CodeRule::kCyclic};

NetColoring Make(int rows, int cols, int colors, std::vector<int> link_colour,
                 ColoringOptions options = {}) {
  NetColoring c;
  c.rows = rows;
  c.cols = cols;
  c.colors = colors;
  c.link_colour = std::move(link_colour);
  c.options = options;
  return c;
}

TEST(NetColoringGeometry, LinksFollowTheSimulatorOrder) {
  // 2 x 3 knots: horizontal (0,0)-(0,1), (0,1)-(0,2), (1,0)-(1,1), (1,1)-(1,2), then vertical.
  EXPECT_EQ(NumLinks(2, 3), 7);
  EXPECT_EQ(LinkKnots(2, 3, 0), (std::array<int, 4>{0, 0, 0, 1}));
  EXPECT_EQ(LinkKnots(2, 3, 3), (std::array<int, 4>{1, 1, 1, 2}));
  EXPECT_EQ(LinkKnots(2, 3, 4), (std::array<int, 4>{0, 0, 1, 0}));
  EXPECT_EQ(LinkKnots(2, 3, 6), (std::array<int, 4>{0, 2, 1, 2}));
  // Knot (0,1): right (0,1)-(0,2) = 1, down (0,1)-(1,1) = 5, left (0,0)-(0,1) = 0.
  EXPECT_EQ(KnotLinks(2, 3, 0, 1), (std::vector<int>{1, 5, 0}));
}

TEST(KnotCode, CyclicTreatsRotationsAndMirrorImagesAsEqual) {
  const std::vector<int> base{0, 1, 2, 3};
  const std::vector<int> code = KnotCode(CodeRule::kCyclic, base);
  EXPECT_EQ(KnotCode(CodeRule::kCyclic, {1, 2, 3, 0}), code);  // rotation
  EXPECT_EQ(KnotCode(CodeRule::kCyclic, {2, 3, 0, 1}), code);  // rotation
  EXPECT_EQ(KnotCode(CodeRule::kCyclic, {3, 2, 1, 0}), code);  // mirror
  EXPECT_EQ(KnotCode(CodeRule::kCyclic, {1, 0, 3, 2}), code);  // mirror of a rotation
  EXPECT_NE(KnotCode(CodeRule::kCyclic, {0, 2, 1, 3}), code);  // a different cyclic order
  // Opposite vs. neighbouring equal colours: same multiset, different cyclic codes.
  EXPECT_EQ(KnotCode(CodeRule::kMultiset, {0, 0, 1, 1}),
            KnotCode(CodeRule::kMultiset, {0, 1, 0, 1}));
  EXPECT_NE(KnotCode(CodeRule::kCyclic, {0, 0, 1, 1}), KnotCode(CodeRule::kCyclic, {0, 1, 0, 1}));
  EXPECT_EQ(KnotCode(CodeRule::kCyclic, {0, 0, 1, 1}), KnotCode(CodeRule::kCyclic, {1, 0, 0, 1}));
  EXPECT_EQ(KnotCode(CodeRule::kSet, {2, 0, 2, 0}), (std::vector<int>{0, 2}));
  EXPECT_EQ(KnotDistance(CodeRule::kCyclic, {0, 1, 2, 3}, {3, 2, 1, 0}), 0);
  EXPECT_EQ(KnotDistance(CodeRule::kCyclic, {0, 0, 1, 1}, {0, 1, 0, 1}), 2);
}

TEST(KnotDistance, FollowsTheDefinitionPerRule) {
  // Multiset: 4 - |{0,1} common| = 2... {0,0,1,1} vs {0,1,1,2}: common {0,1,1} -> 1.
  EXPECT_EQ(KnotDistance(CodeRule::kMultiset, {0, 0, 1, 1}, {0, 1, 1, 2}), 1);
  // Set: (0,0,0,1) -> {0,1,2} needs 1 change, (0,1,2,2) -> {0,1} needs 2: the smaller, 1.
  EXPECT_EQ(KnotDistance(CodeRule::kSet, {0, 0, 0, 1}, {0, 1, 2, 2}), 1);
  EXPECT_EQ(KnotDistance(CodeRule::kSet, {1, 1, 2, 2}, {3, 3, 3, 3}), 4);
  // Set: (0,0,0,0) -> {0,1,2,3} needs 3 changes.
  EXPECT_EQ(KnotDistance(CodeRule::kSet, {0, 0, 0, 0}, {0, 1, 2, 3}), 3);
  EXPECT_EQ(KnotDistance(CodeRule::kSet, {0, 1}, {1, 0}), 0);
  EXPECT_GE(KnotDistance(CodeRule::kSet, {0, 1}, {0, 1, 2}), kFarDistance);  // other degree
}

// Independent code function for the counting check and the exhaustive search.
std::vector<int> TestCode(CodeRule rule, std::vector<int> x) {
  if (rule == CodeRule::kSet) {
    std::set<int> s(x.begin(), x.end());
    return {s.begin(), s.end()};
  }
  if (rule == CodeRule::kMultiset || x.size() <= 1) {
    std::sort(x.begin(), x.end());
    return x;
  }
  std::vector<int> best;
  const int d = static_cast<int>(x.size());
  for (int start = 0; start < d; ++start)
    for (int step : {1, d - 1}) {
      std::vector<int> y;
      for (int i = 0; i < d; ++i) y.push_back(x[(start + i * step) % d]);
      if (best.empty() || y < best) best = y;
    }
  return best;
}

std::vector<std::vector<int>> AllConfigs(int d, int k) {
  std::vector<std::vector<int>> out;
  std::vector<int> x(d, 0);
  while (true) {
    out.push_back(x);
    int i = 0;
    while (i < d && ++x[i] == k) x[i++] = 0;
    if (i == d) break;
  }
  return out;
}

TEST(CountCodes, MatchesEnumeration) {
  for (CodeRule rule : kRules)
    for (bool adj : {false, true})
      for (int d = 1; d <= 4; ++d)
        for (int k = 1; k <= 5; ++k) {
          std::set<std::vector<int>> codes;
          for (const auto& x : AllConfigs(d, k)) {
            if (adj && std::set<int>(x.begin(), x.end()).size() != x.size()) continue;
            codes.insert(TestCode(rule, x));
          }
          EXPECT_EQ(CountCodes(rule, d, k, adj), static_cast<int64_t>(codes.size()))
              << CodeRuleName(rule) << " d=" << d << " k=" << k << " adj=" << adj;
        }
}

// 2 x 2 knots: links h(0,0)-(0,1)=0, h(1,0)-(1,1)=1, v(0,0)-(1,0)=2, v(0,1)-(1,1)=3.
// Colours 0,2,0,1 give the knots {0}, {0,1}, {0,2}, {1,2}.
TEST(VerifyColoring, AcceptsAGoodColouring) {
  std::string why;
  EXPECT_TRUE(VerifyColoring(Make(2, 2, 3, {0, 2, 0, 1}), &why)) << why;
}

TEST(VerifyColoring, CatchesADuplicateCode) {
  std::string why;
  EXPECT_FALSE(VerifyColoring(Make(2, 2, 3, {0, 2, 0, 0}), &why));
  EXPECT_NE(why.find("knot (0, 0) and knot (0, 1)"), std::string::npos) << why;
  EXPECT_NE(why.find("{0}"), std::string::npos) << why;
}

TEST(VerifyColoring, CatchesADistanceOnePairWhenTwoAreRequired) {
  ColoringOptions o;
  o.min_distance = 2;
  std::string why;
  EXPECT_FALSE(VerifyColoring(Make(2, 2, 3, {0, 2, 0, 1}, o), &why));  // {0} vs {0,1}: 1 change
  EXPECT_NE(why.find("distance 1 < min_distance 2"), std::string::npos) << why;
  // 3 x 3, D = 2 multiset: the edge knots share at most one colour with each other.
  o.rule = CodeRule::kMultiset;
  const NetColoring solved = SolveColoring(3, 3, o);
  EXPECT_TRUE(VerifyColoring(solved, &why)) << why;
  NetColoring broken = solved;
  // Make knot (0,0) read like knot (0,2) up to one link: copy (0,2)'s down link onto (0,0)'s.
  broken.link_colour[KnotLinks(3, 3, 0, 0)[1]] = broken.link_colour[KnotLinks(3, 3, 0, 2)[0]];
  broken.link_colour[KnotLinks(3, 3, 0, 0)[0]] = broken.link_colour[KnotLinks(3, 3, 0, 2)[1]];
  EXPECT_FALSE(VerifyColoring(broken, &why));
}

TEST(VerifyColoring, CatchesAnAdjacencyViolation) {
  ColoringOptions o;
  o.adjacent_distinct = true;
  std::string why;
  EXPECT_FALSE(VerifyColoring(Make(2, 2, 3, {0, 2, 0, 1}, o), &why));  // knot (0,0): 0,0
  EXPECT_NE(why.find("knot (0, 0): two links share colour 0"), std::string::npos) << why;
  EXPECT_TRUE(VerifyColoring(Make(2, 2, 4, {0, 1, 2, 3}, o), &why)) << why;
}

TEST(VerifyColoring, RespectsTheRadius) {
  // 1 x 5 knots, links 0..3 coloured 0,1,2,0: both ends read {0}, four links apart; the middle
  // knots {0,1}, {1,2}, {0,2} differ.
  ColoringOptions o;
  std::string why;
  o.radius = 2;
  EXPECT_TRUE(VerifyColoring(Make(1, 5, 3, {0, 1, 2, 0}, o), &why)) << why;
  o.radius = 4;
  EXPECT_FALSE(VerifyColoring(Make(1, 5, 3, {0, 1, 2, 0}, o), &why));
  EXPECT_NE(why.find("4 links apart"), std::string::npos) << why;
  o.radius = 0;
  EXPECT_FALSE(VerifyColoring(Make(1, 5, 3, {0, 1, 2, 0}, o), &why));
  o.radius = 2;
  EXPECT_FALSE(VerifyColoring(Make(1, 5, 3, {0, 1, 0, 0}, o), &why));  // {0,1},{0,1} 1 apart
}

TEST(VerifyColoring, RejectsColoursOutsideThePalette) {
  std::string why;
  EXPECT_FALSE(VerifyColoring(Make(2, 2, 2, {0, 2, 0, 1}), &why));
  EXPECT_NE(why.find("link 1"), std::string::npos) << why;
}

// The verifier compares pairs within the radius or looks codes up in a table, whichever is
// cheaper; either way its verdict must be that of comparing every pair (graph distance on the
// grid by breadth-first search here), on valid colourings and on ones with a link changed.
bool AllPairsValid(const NetColoring& c) {
  const int n = c.rows * c.cols;
  std::vector<std::vector<int>> colours(n);
  for (int x = 0; x < n; ++x) colours[x] = KnotLinkColours(c, x / c.cols, x % c.cols);
  for (int x = 0; x < n; ++x) {
    std::vector<int> hops(n, -1);
    std::vector<int> queue{x};
    hops[x] = 0;
    for (size_t i = 0; i < queue.size(); ++i) {
      const int y = queue[i], r = y / c.cols, col = y % c.cols;
      for (auto [nr, nc] : {std::pair(r, col + 1), std::pair(r + 1, col), std::pair(r, col - 1),
                            std::pair(r - 1, col)}) {
        if (nr < 0 || nr >= c.rows || nc < 0 || nc >= c.cols || hops[nr * c.cols + nc] >= 0)
          continue;
        hops[nr * c.cols + nc] = hops[y] + 1;
        queue.push_back(nr * c.cols + nc);
      }
    }
    for (int w = x + 1; w < n; ++w)
      if ((c.options.radius == 0 || hops[w] <= c.options.radius) &&
          KnotDistance(c.options.rule, colours[x], colours[w]) < c.options.min_distance)
        return false;
  }
  return true;
}

TEST(VerifyColoring, AgreesWithComparingEveryPair) {
  int valid = 0, invalid = 0;
  for (CodeRule rule : kRules)
    for (int d : {1, 2})
      for (int radius : {0, 2})
        for (auto [rows, cols] : {std::pair(4, 5), std::pair(9, 9)}) {
          ColoringOptions o;
          o.rule = rule;
          o.min_distance = d;
          o.radius = radius;
          o.time_limit_s = 0.2;
          const NetColoring solved = SolveColoring(rows, cols, o);
          ASSERT_GT(solved.colors, 0);
          for (int link = 0; link < NumLinks(rows, cols); link += 7) {
            NetColoring c = solved;
            if (link > 0) c.link_colour[link] = (c.link_colour[link] + link) % c.colors;
            std::string why;
            const bool expected = AllPairsValid(c);
            EXPECT_EQ(VerifyColoring(c, &why), expected)
                << CodeRuleName(rule) << " D=" << d << " R=" << radius << " " << rows << "x" << cols
                << " link " << link << ": " << why;
            ++(expected ? valid : invalid);
          }
        }
  EXPECT_GT(valid, 20);
  EXPECT_GT(invalid, 20);
}

// The memory estimate grows with the knots within the radius (the partner lists), and the
// default search over the largest accepted net fits a workstation.
TEST(EstimateColoringBytes, GrowsWithTheNetAndTheRadius) {
  ColoringOptions o;
  o.rule = CodeRule::kCyclic;
  const double whole = EstimateColoringBytes(1000, 1000, o);
  EXPECT_LT(whole, 4e9);
  EXPECT_GT(whole, 2e6 * o.max_colors * 4);  // at least the tabu tenures, links x colours
  EXPECT_LT(EstimateColoringBytes(100, 100, o), whole / 50);
  o.radius = 3;
  const double r3 = EstimateColoringBytes(1000, 1000, o);
  o.radius = 30;
  const double r30 = EstimateColoringBytes(1000, 1000, o);
  // Partner lists: 4 bytes x 10^6 knots x (2 R^2 + 2 R) knots within R.
  EXPECT_GT(r30 - r3, 4e6 * (2 * 900 + 60 - 2 * 9 - 6) * 0.99);
  EXPECT_LT(r30 - r3, 4e6 * (2 * 900 + 60 - 2 * 9 - 6) * 1.01);
  o.radius = 999;
  EXPECT_GT(EstimateColoringBytes(1000, 1000, o), 1e12);
}

TEST(SolveColoring, EveryResultPassesTheVerifier) {
  for (CodeRule rule : kRules)
    for (int d : {1, 2})
      for (bool adj : {false, true})
        for (int radius : {0, 2})
          for (auto [rows, cols] : {std::pair(3, 3), std::pair(4, 5), std::pair(6, 6)}) {
            ColoringOptions o;
            o.rule = rule;
            o.min_distance = d;
            o.adjacent_distinct = adj;
            o.radius = radius;
            o.time_limit_s = 0.05;
            const NetColoring c = SolveColoring(rows, cols, o);
            const std::string what = CodeRuleName(rule) + " D=" + std::to_string(d) +
                                     " adj=" + std::to_string(adj) +
                                     " R=" + std::to_string(radius) + " " + std::to_string(rows) +
                                     "x" + std::to_string(cols);
            ASSERT_GT(c.colors, 0) << what;
            EXPECT_GE(c.colors, c.lower_bound) << what;
            std::string why;
            EXPECT_TRUE(VerifyColoring(c, &why)) << what << ": " << why;
          }
}

// Distances by their definition between all configurations of d links with k colours (in
// AllConfigs order): the fewest link changes that give one knot the other's code, the smaller
// of the two directions.
std::vector<std::vector<int>> DefinitionDistances(CodeRule rule, int d, int k) {
  const auto configs = AllConfigs(d, k);
  std::map<std::vector<int>, int> code_id;
  for (const auto& x : configs) code_id.emplace(TestCode(rule, x), code_id.size());
  // change[x][code] = fewest changes of x reaching a configuration with that code.
  std::vector<std::vector<int>> change(configs.size(), std::vector<int>(code_id.size(), 99));
  for (size_t a = 0; a < configs.size(); ++a)
    for (const auto& y : configs) {
      int h = 0;
      for (int i = 0; i < d; ++i) h += configs[a][i] != y[i];
      int& slot = change[a][code_id[TestCode(rule, y)]];
      slot = std::min(slot, h);
    }
  std::vector<std::vector<int>> dist(configs.size(), std::vector<int>(configs.size()));
  for (size_t a = 0; a < configs.size(); ++a)
    for (size_t b = 0; b < configs.size(); ++b)
      dist[a][b] = std::min(change[a][code_id[TestCode(rule, configs[b])]],
                            change[b][code_id[TestCode(rule, configs[a])]]);
  return dist;
}

// The distance-2 search's keys meet exactly when two knots are at most one change apart.
TEST(DistanceTwoKeys, MeetExactlyWithinOneChange) {
  for (CodeRule rule : kRules)
    for (int d = 1; d <= 4; ++d) {
      const int k = d <= 3 ? 5 : 4;
      const auto configs = AllConfigs(d, k);
      const auto dist = DefinitionDistances(rule, d, k);
      int meeting = 0;
      for (size_t a = 0; a < configs.size(); ++a)
        for (size_t b = 0; b < configs.size(); ++b) {
          const bool meet = DistanceTwoKeysMeet(rule, configs[a], configs[b]);
          ASSERT_EQ(meet, dist[a][b] <= 1)
              << CodeRuleName(rule) << " " << ::testing::PrintToString(configs[a]) << " vs "
              << ::testing::PrintToString(configs[b]) << ": distance " << dist[a][b];
          meeting += meet;
        }
      EXPECT_GT(meeting, static_cast<int>(configs.size()));  // not only the equal pairs
    }
  // Knots of different degree never meet.
  EXPECT_FALSE(DistanceTwoKeysMeet(CodeRule::kSet, {0, 1}, {0, 1, 1}));
}

// Largest set of codes pairwise >= D apart (by definition), by branch and bound over a bitset
// clique complement; nodes are codes (multisets for the set rule, whose distance depends on the
// multiplicities), restricted to all-distinct colours with `distinct`.
int ExhaustivePacking(CodeRule rule, int d, int k, bool distinct, int min_distance) {
  const auto configs = AllConfigs(d, k);
  const auto dist = DefinitionDistances(rule, d, k);
  const CodeRule node_rule = rule == CodeRule::kSet ? CodeRule::kMultiset : rule;
  std::map<std::vector<int>, size_t> node_of;  // code -> one configuration index
  for (size_t a = 0; a < configs.size(); ++a) {
    if (distinct && std::set<int>(configs[a].begin(), configs[a].end()).size() != configs[a].size())
      continue;
    node_of.emplace(TestCode(node_rule, configs[a]), a);
  }
  std::vector<size_t> nodes;
  for (const auto& [code, a] : node_of) nodes.push_back(a);
  const size_t n = nodes.size();
  EXPECT_LE(n, 128u);
  using Bits = std::bitset<128>;
  std::vector<Bits> conflict(n);
  for (size_t i = 0; i < n; ++i)
    for (size_t j = 0; j < n; ++j)
      if (i != j && dist[nodes[i]][nodes[j]] < min_distance) conflict[i].set(j);
  int best = 0;
  std::function<void(Bits, int)> grow = [&](Bits candidates, int size) {
    if (size + static_cast<int>(candidates.count()) <= best) return;
    if (candidates.none()) {
      best = size;
      return;
    }
    const size_t v = candidates._Find_first();
    Bits without_v = candidates;
    without_v.reset(v);
    grow(without_v & ~conflict[v], size + 1);
    grow(without_v, size);
  };
  Bits all;
  for (size_t i = 0; i < n; ++i) all.set(i);
  grow(all, 0);
  return best;
}

TEST(MaxCodePacking, NeverBelowTheExhaustiveMaximum) {
  int tight = 0;
  for (CodeRule rule : kRules)
    for (bool distinct : {false, true})
      for (int d = 2; d <= 4; ++d)
        for (int k = d <= 3 ? 3 : 3; k <= (d == 2 ? 6 : d == 3 ? 6 : 4); ++k)
          for (int min_distance = 2; min_distance <= d; ++min_distance) {
            const int exact = ExhaustivePacking(rule, d, k, distinct, min_distance);
            const int64_t bound = MaxCodePacking(rule, d, k, distinct, min_distance);
            EXPECT_GE(bound, exact) << CodeRuleName(rule) << " d=" << d << " k=" << k
                                    << " distinct=" << distinct << " D=" << min_distance;
            tight += bound == exact;
          }
  // The bound is an LP relaxation; it is exact on most of these small cases.
  EXPECT_GE(tight, 40);
}

// Multiset, 4 links, D = 2: the linear programme's optimum in closed form, k + C(k,2) + C(k,3)/4
// (every 3-sub-multiset in at most one code; abcd codes use four, aabb / aabc two of the aab).
TEST(MaxCodePacking, MatchesTheClosedFormForFourLinkMultisets) {
  for (int k = 2; k <= 30; ++k) {
    const double closed = k + k * (k - 1) / 2.0 + k * (k - 1) * (k - 2) / 24.0;
    EXPECT_EQ(MaxCodePacking(CodeRule::kMultiset, 4, k, false, 2),
              static_cast<int64_t>(std::floor(closed + 1e-9)))
        << k;
  }
}

// Exhaustive, independent of the solver: does any colouring with k colours satisfy the options?
// Colourings in restricted-growth form (colour i appears only after 0..i-1), which loses nothing
// since renaming colours keeps every rule. Distances by their definition over all configurations.
class Exhaustive {
 public:
  Exhaustive(int rows, int cols, const ColoringOptions& o, int k)
      : rows_(rows), cols_(cols), o_(o), k_(k) {
    for (int d = 1; d <= 4; ++d) dist_[d] = DefinitionDistances(o.rule, d, k);
    for (int r = 0; r < rows; ++r)
      for (int c = 0; c < cols; ++c) knots_.push_back(KnotLinks(rows, cols, r, c));
  }

  bool AnyValid() {
    colour_.assign(NumLinks(rows_, cols_), 0);
    return Enumerate(0, -1);
  }

 private:
  bool Enumerate(size_t i, int max_used) {
    if (i == colour_.size()) return Valid();
    for (int c = 0; c <= std::min(k_ - 1, max_used + 1); ++c) {
      colour_[i] = c;
      if (Enumerate(i + 1, std::max(max_used, c))) return true;
    }
    return false;
  }
  int Index(const std::vector<int>& links) const {
    int idx = 0;
    for (int i = static_cast<int>(links.size()) - 1; i >= 0; --i)
      idx = idx * k_ + colour_[links[i]];
    return idx;
  }
  bool Valid() const {
    const int n = static_cast<int>(knots_.size());
    for (int x = 0; x < n; ++x) {
      if (o_.adjacent_distinct)
        for (size_t i = 0; i < knots_[x].size(); ++i)
          for (size_t j = i + 1; j < knots_[x].size(); ++j)
            if (colour_[knots_[x][i]] == colour_[knots_[x][j]]) return false;
      for (int w = x + 1; w < n; ++w) {
        if (knots_[w].size() != knots_[x].size()) continue;
        const int hops = std::abs(x / cols_ - w / cols_) + std::abs(x % cols_ - w % cols_);
        if (o_.radius > 0 && hops > o_.radius) continue;
        if (dist_.at(static_cast<int>(knots_[x].size())).at(Index(knots_[x])).at(Index(knots_[w])) <
            o_.min_distance)
          return false;
      }
    }
    return true;
  }

  int rows_, cols_;
  ColoringOptions o_;
  int k_;
  std::map<int, std::vector<std::vector<int>>> dist_;
  std::vector<std::vector<int>> knots_;
  std::vector<int> colour_;
};

// The set rule at distance 2 on a larger net (the keyed search's four key families): the result
// must hold under the set rule's own distance.
TEST(SolveColoring, LargeSetNetsAtDistanceTwoPassTheVerifier) {
  ColoringOptions o;
  o.rule = CodeRule::kSet;
  o.min_distance = 2;
  o.time_limit_s = 1.0;
  const NetColoring c = SolveColoring(13, 13, o);
  ASSERT_GT(c.colors, 0) << c.method;
  std::string why;
  EXPECT_TRUE(VerifyColoring(c, &why)) << why;
  EXPECT_GE(c.colors, c.lower_bound);
}

TEST(SolveColoring, OptimalityClaimsHoldUnderExhaustiveSearch) {
  int checked = 0;
  for (CodeRule rule : kRules)
    for (int d : {1, 2})
      for (bool adj : {false, true})
        for (auto [rows, cols] :
             {std::pair(2, 2), std::pair(2, 3), std::pair(3, 3), std::pair(3, 4)}) {
          ColoringOptions o;
          o.rule = rule;
          o.min_distance = d;
          o.adjacent_distinct = adj;
          o.time_limit_s = 0.3;
          const NetColoring c = SolveColoring(rows, cols, o);
          const std::string what = CodeRuleName(rule) + " D=" + std::to_string(d) +
                                   " adj=" + std::to_string(adj) + " " + std::to_string(rows) +
                                   "x" + std::to_string(cols) + " k=" + std::to_string(c.colors);
          if (d == 2 && rows == 2) {
            // Adjacent corners share a link, so they are at most 1 apart: no palette works.
            EXPECT_EQ(c.method, "infeasible") << what;
            EXPECT_EQ(c.colors, 0) << what;
            EXPECT_FALSE(Exhaustive(rows, cols, o, 3).AnyValid()) << what;
            continue;
          }
          ASSERT_GT(c.colors, 0) << what;
          if (!c.optimal || c.colors <= 1) continue;
          // Enumeration size ~ (k-1)^L / (k-1)!; keep the test fast.
          const int k = c.colors - 1, links = NumLinks(rows, cols);
          double size = 1;
          for (int i = 0; i < links; ++i) size *= k;
          for (int i = 2; i <= k; ++i) size /= i;
          if (size > 2e5 || k > 4) continue;
          EXPECT_FALSE(Exhaustive(rows, cols, o, k).AnyValid()) << what << ": k-1 colours work";
          ++checked;
        }
  EXPECT_GE(checked, 20);
}

TEST(ColoringLowerBound, NeverExceedsTheExhaustiveOptimum) {
  for (CodeRule rule : kRules)
    for (int d : {1, 2})
      for (int radius : {0, 2})
        for (auto [rows, cols] : {std::pair(2, 2), std::pair(2, 3), std::pair(3, 3)}) {
          ColoringOptions o;
          o.rule = rule;
          o.min_distance = d;
          o.radius = radius;
          const int bound = ColoringLowerBound(rows, cols, o);
          if (bound <= 1 || bound > 64) continue;
          EXPECT_FALSE(Exhaustive(rows, cols, o, bound - 1).AnyValid())
              << CodeRuleName(rule) << " D=" << d << " R=" << radius << " " << rows << "x" << cols;
        }
}

TEST(ColoringFile, RoundTrips) {
  ScratchDir dir("coloring");
  ColoringOptions o;
  o.rule = CodeRule::kCyclic;
  o.radius = 3;
  NetColoring c = SolveColoring(4, 4, o);
  c.palette_names.assign(c.colors, "");
  for (int i = 0; i < c.colors; ++i) c.palette_names[i] = "yarn " + std::to_string(i);
  std::vector<std::array<int, 3>> srgb;
  for (int i = 0; i < c.colors; ++i) srgb.push_back({10 * i, 255 - i, 7});
  const std::string path = (dir.path() / "coloring.yaml").string();
  WriteColoring(path, c, srgb);
  std::vector<std::array<int, 3>> srgb_read;
  const NetColoring r = ReadColoring(path, &srgb_read);
  EXPECT_EQ(r.rows, 4);
  EXPECT_EQ(r.colors, c.colors);
  EXPECT_EQ(r.link_colour, c.link_colour);
  EXPECT_EQ(r.options.rule, CodeRule::kCyclic);
  EXPECT_EQ(r.options.radius, 3);
  EXPECT_EQ(r.optimal, c.optimal);
  EXPECT_EQ(r.method, c.method);
  EXPECT_EQ(r.palette_names, c.palette_names);
  EXPECT_EQ(srgb_read, srgb);
  EXPECT_FALSE(std::filesystem::exists(path + ".partial"));
}

std::string ReadError(const std::string& path, const std::string& text) {
  { std::ofstream(path) << text; }
  try {
    ReadColoring(path);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(ColoringFile, BadFilesNameLineAndKey) {
  ScratchDir dir("coloring_bad");
  const std::string path = (dir.path() / "c.yaml").string();
  const std::string head = "rows: 2\ncols: 2\nrule: set\ncolors: 3\nlinks:\n";
  const std::string good_links =
      "  - {a: [0, 0], b: [0, 1], colour: 0}\n  - {a: [1, 0], b: [1, 1], colour: 2}\n"
      "  - {a: [0, 0], b: [1, 0], colour: 0}\n  - {a: [0, 1], b: [1, 1], colour: 1}\n";
  EXPECT_EQ(ReadError(path, head + good_links), "");
  // Colour out of range on line 7.
  std::string e = ReadError(path, head +
                                      "  - {a: [0, 0], b: [0, 1], colour: 0}\n"
                                      "  - {a: [1, 0], b: [1, 1], colour: 5}\n"
                                      "  - {a: [0, 0], b: [1, 0], colour: 0}\n"
                                      "  - {a: [0, 1], b: [1, 1], colour: 1}\n");
  EXPECT_NE(e.find("c.yaml:7: links[1].colour: must be in 0..2"), std::string::npos) << e;
  // Not neighbours.
  e = ReadError(path, head +
                          "  - {a: [0, 0], b: [1, 1], colour: 0}\n"
                          "  - {a: [1, 0], b: [1, 1], colour: 2}\n"
                          "  - {a: [0, 0], b: [1, 0], colour: 0}\n"
                          "  - {a: [0, 1], b: [1, 1], colour: 1}\n");
  EXPECT_NE(e.find("c.yaml:6: links[0].b: knots a and b are not neighbours"), std::string::npos)
      << e;
  // Unknown rule.
  e = ReadError(path, "rows: 2\ncols: 2\nrule: colours\ncolors: 3\nlinks:\n" + good_links);
  EXPECT_NE(e.find("c.yaml:3: rule: expected set, multiset or cyclic"), std::string::npos) << e;
  // Valid syntax, but two knots share a code.
  e = ReadError(path, head +
                          "  - {a: [0, 0], b: [0, 1], colour: 0}\n"
                          "  - {a: [1, 0], b: [1, 1], colour: 0}\n"
                          "  - {a: [0, 0], b: [1, 0], colour: 0}\n"
                          "  - {a: [0, 1], b: [1, 1], colour: 1}\n");
  EXPECT_NE(e.find("breaks its own rule"), std::string::npos) << e;
}

}  // namespace
}  // namespace netlab::recon
