#pragma once
// Yarn colouring of a net so that every knot is identified by the colours of its links.
//
// The net is a grid of rows x cols knots; links join horizontal and vertical neighbours. Link
// order (the contract shared with the simulator, libnetsim/model/model.h): first the horizontal
// links (r,c)-(r,c+1) row by row, then the vertical links (r,c)-(r+1,c) row by row.
//
// A knot's links in GEOMETRIC ORDER are the present ones among right, down, left, up (in that
// order, absent links skipped). A knot's CODE under a rule:
//   kSet       the set of distinct colours;
//   kMultiset  the multiset of colours;
//   kCyclic    the cyclic sequence in geometric order, equal up to rotation and mirror image
//              (the dihedral group of the present links). For degree <= 3 every permutation is a
//              rotation or mirror, so there it equals the multiset; it differs only at 4-link
//              knots.
// Degree is visible in the image, so only knots of equal degree are compared.
//
// DISTANCE between two knots A and B of equal degree d, with link colours a and b in geometric
// order: the fewest link-colour changes that turn one knot's links into a configuration having
// the other's code, the smaller of the two directions:
//   dist(A, B) = min(Change(a -> Code(b)), Change(b -> Code(a))),
//   Change(x -> code) = min { Hamming(x, y) : Code(y) == code }.
// Closed forms: kMultiset d - |a ∩ b| (multiset intersection); kCyclic the least Hamming distance
// between a and a rotation/mirror image of b; kSet max(#links of x whose colour is not in S,
// #colours of S missing from x) for S = Code(target) (no configuration when |S| > d: "infinite").
// dist == 0 exactly when the codes are equal; min_distance D means every constrained pair has
// dist >= D, so D - 1 misread link colours never turn one knot into another.
//
// Constrained pairs: knots of equal degree at graph distance <= radius (radius 0: all of them).

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace netlab::recon {

enum class CodeRule { kSet, kMultiset, kCyclic };

// "set", "multiset", "cyclic"; false (and *rule untouched) for anything else.
bool ParseCodeRule(const std::string& name, CodeRule* rule);
std::string CodeRuleName(CodeRule rule);

struct ColoringOptions {
  CodeRule rule = CodeRule::kSet;
  // Least distance (see above) between constrained knots; 1 = plain uniqueness.
  int min_distance = 1;
  // Constrain only knots within this many links (graph distance); 0 = the whole net.
  int radius = 0;
  // The links of one knot must all have different colours.
  bool adjacent_distinct = false;
  // The largest palette tried.
  int max_colors = 64;
  // The search's budgets, counted in its own steps rather than seconds so that the result depends
  // only on the net and these options, never on the machine's load (a wall-clock budget gave 23,
  // 36 or 44 colours for one 100x100 net): for each palette the heuristic tries, work units per
  // link (a unit is about 50-70 ns here: 4000 per link is ~1 s for 51x51 knots; the last
  // palettes, tried downwards from the first that works, get 4 budgets), and for the exact
  // search in nodes and code comparisons.
  int64_t work_per_link = 4000;
  int64_t exact_work = 100'000'000;
  // Wall-clock cap of SolveColoring, seconds: the search stops there at the latest, and the
  // result says so (NetColoring::time_limited); only such a result may differ between runs.
  double time_limit_s = 30.0;
  // Seed of the heuristic's random choices.
  uint64_t seed = 1;

  // False with a reason for options out of range.
  bool IsValid(std::string* error) const;
};

struct NetColoring {
  int rows = 0, cols = 0, colors = 0;
  std::vector<int> link_colour;  // per link, the contract order above; each in [0, colors)
  ColoringOptions options;
  int lower_bound = 0;   // ColoringLowerBound for these options
  bool optimal = false;  // proven: lower bound reached, or the exact search exhausted colors - 1
  std::string method;    // "heuristic", "exact", "heuristic+exact"; "none" when nothing found
  double wall_s = 0.0;   // time SolveColoring took, seconds
  bool time_limited = false;   // the wall-clock cap cut the search short (see time_limit_s)
  bool exact_skipped = false;  // more than kExactSearchMaxKnots knots: no exact stage was run
  std::vector<std::string> palette_names;  // optional, from a physical palette
};

int NumLinks(int rows, int cols);
// The knots (r0, c0, r1, c1) of `link` (contract order).
std::array<int, 4> LinkKnots(int rows, int cols, int link);
// The link ids at knot (r, c) in geometric order (right, down, left, up; absent ones skipped).
std::vector<int> KnotLinks(int rows, int cols, int r, int c);
// The colours of those links.
std::vector<int> KnotLinkColours(const NetColoring& coloring, int r, int c);

// Canonical code of a knot from its link colours in geometric order: sorted distinct colours
// (kSet), sorted colours (kMultiset), the lexicographically least rotation / mirror image
// (kCyclic). Two knots have the same code exactly when these vectors are equal.
std::vector<int> KnotCode(CodeRule rule, const std::vector<int>& colours);
// "{0,2}" for sets and multisets, "(0,1,0,2)" for cyclic codes.
std::string CodeString(CodeRule rule, const std::vector<int>& code);
// The distance above between knots with link colours a and b (geometric order); a large value
// (kFarDistance) when the degrees differ or no configuration reaches the other code.
constexpr int kFarDistance = 1000;
int KnotDistance(CodeRule rule, const std::vector<int>& a, const std::vector<int>& b);

// Codes available to a knot of `degree` with k colours (all of them, or with all-different
// link colours when adjacent_distinct), and an upper bound on how many of them can be pairwise
// at distance >= min_distance. For D >= 2 the bound is a packing argument: a code with D - 1
// links wildcarded (a KEY) is shared by any two codes fewer than D apart, so codes pairwise D
// apart own disjoint sets of keys; the optimum of the linear programme "most codes, each key
// pattern used at most as often as it has keys", with one variable per code pattern (aabc, abab,
// ... up to renaming of colours), bounds the packing. Multiset and cyclic directly; set by the
// multiset bound (a set distance never exceeds the multiset distance) and its own code count.
// Saturates at 2^62.
int64_t CountCodes(CodeRule rule, int degree, int k, bool adjacent_distinct);
int64_t MaxCodePacking(CodeRule rule, int degree, int k, bool adjacent_distinct, int min_distance);

// Whether the distance-2 search's keys of two knots (link colours in geometric order) meet: by
// construction exactly when KnotDistance(rule, a, b) <= 1 (exposed for the tests).
bool DistanceTwoKeysMeet(CodeRule rule, const std::vector<int>& a, const std::vector<int>& b);

// The lower bound: the fewest colours k for which, for every degree, MaxCodePacking is at least
// the largest set of knots of that degree that pairwise must differ (all of them for radius 0,
// otherwise the most that fit in one diamond of graph diameter <= radius); at least the maximum
// degree with adjacent_distinct. 0 for a net without links.
int ColoringLowerBound(int rows, int cols, const ColoringOptions& options);

// The exact search's limit: its partner lists hold every pair of knots of one degree at radius
// 0 (n^2 entries; 4 TB at 1000x1000) and it recurses once per link, while above ~30x30 knots it
// cannot prove anything within any budget anyway.
constexpr int kExactSearchMaxKnots = 1024;

// The memory SolveColoring, VerifyColoring and WriteColoring need for a net of rows x cols knots
// under these options, bytes (an upper estimate, for refusing a run before it allocates): the
// net, the heuristic's state (the tabu list, links x max_colors), its code counts or distance-2
// keys, the partner lists where the search reads them (same-degree knots within the radius:
// about n (2R^2 + 2R) entries), and the written file's text.
double EstimateColoringBytes(int rows, int cols, const ColoringOptions& options);

// The fewest colours found: the heuristic (random start + tabu min-conflicts search) from the
// lower bound upwards, then the exact search (backtracking, links in knot order, colours
// introduced in increasing order, code conflicts checked as each knot completes) to prove
// colors - 1 infeasible within its work budget; nets above kExactSearchMaxKnots skip it
// (exact_skipped). method "none" and colors 0 when nothing was found up to max_colors within the
// budgets; method "infeasible" when the lower bound exceeds max_colors.
NetColoring SolveColoring(int rows, int cols, const ColoringOptions& options);

// Exact search alone with k colours: 1 found (*link_colour set), 0 proven infeasible, -1 budget
// (options.exact_work) or time up. Throws std::invalid_argument above kExactSearchMaxKnots.
int ExactColoring(int rows, int cols, const ColoringOptions& options, int k, double time_limit_s,
                  std::vector<int>* link_colour);

// Independent check, with codes recomputed from the link list: false with the first violation
// named (which knots, which codes) in *why. Time and memory O(n) for radius 0 (every knot's
// configurations within min_distance - 1 changes looked up in a table of codes), O(n R^2) with
// a radius (the knots within R links compared), never more than comparing all pairs.
bool VerifyColoring(const NetColoring& coloring, std::string* why);

// coloring.yaml: rows, cols, rule, min_distance, radius, adjacent_distinct, colors, lower_bound,
// optimal, method, palette (list of {name, srgb: [r, g, b] 0..255 optional}) and links as
// {a: [r, c], b: [r, c], colour: i} in contract order. Written to path.partial, then renamed.
void WriteColoring(const std::string& path, const NetColoring& coloring,
                   const std::vector<std::array<int, 3>>& palette_srgb = {});
// Reads and checks everything (keys, ranges, each link once, the colouring valid under its own
// rule); throws netlab::InputError naming file, line and key.
NetColoring ReadColoring(const std::string& path,
                         std::vector<std::array<int, 3>>* palette_srgb = nullptr);

}  // namespace netlab::recon
