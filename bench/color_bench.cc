// Yarn colouring benchmark: the fewest colours SolveColoring finds for square nets, against the
// counting lower bound, and whether the result is proven optimal.
//
//   bench_color [--time S]   (per-case time limit, default 4 s)
//
// Cases: 6, 11, 17, 26 and 51 knots square; rules set, multiset, cyclic; min_distance 1 and 2;
// radius 0 (whole net); adjacency off, plus set / D = 1 and multiset / D = 2 with adjacency on,
// and set / D = 1 and 2 with uniqueness only within 3 links (tracking supplies the rest). Every
// result is checked by VerifyColoring (a failure is printed in the table, never hidden).

#include <cstdio>
#include <cstring>
#include <string>

#include "libreconstruct/coloring/net_coloring.h"

int main(int argc, char** argv) {
  using namespace netlab::recon;
  double time_s = 4.0;
  for (int i = 1; i + 1 < argc; ++i)
    if (std::strcmp(argv[i], "--time") == 0) time_s = std::atof(argv[++i]);
  std::printf("Per-case time limit %.1f s.\n\n", time_s);
  std::printf("| knots | rule | D | adjacent distinct | radius | colours | lower bound | optimal | "
              "method | time (s) | verified |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|---|---|\n");
  struct Case {
    CodeRule rule;
    int d;
    bool adj;
    int radius = 0;
  };
  std::vector<Case> cases;
  for (CodeRule rule : {CodeRule::kSet, CodeRule::kMultiset, CodeRule::kCyclic})
    for (int d : {1, 2}) cases.push_back({rule, d, false});
  cases.push_back({CodeRule::kSet, 1, true});
  cases.push_back({CodeRule::kMultiset, 2, true});
  cases.push_back({CodeRule::kSet, 1, false, 3});
  cases.push_back({CodeRule::kSet, 2, false, 3});
  for (int n : {6, 11, 17, 26, 51})
    for (const Case& c : cases) {
      ColoringOptions o;
      o.rule = c.rule;
      o.min_distance = c.d;
      o.adjacent_distinct = c.adj;
      o.radius = c.radius;
      o.time_limit_s = time_s;
      const NetColoring result = SolveColoring(n, n, o);
      std::string why;
      const char* verified = "-";
      if (result.colors > 0) verified = VerifyColoring(result, &why) ? "yes" : "NO";
      std::printf("| %dx%d | %s | %d | %s | %d | %d | %d | %s | %s | %.2f | %s |\n", n, n,
                  CodeRuleName(c.rule).c_str(), c.d, c.adj ? "on" : "off", c.radius, result.colors,
                  result.lower_bound, result.optimal ? "yes" : "no", result.method.c_str(),
                  result.wall_s, verified);
      if (!why.empty()) std::printf("  verification failed: %s\n", why.c_str());
      std::fflush(stdout);
    }
  return 0;
}
