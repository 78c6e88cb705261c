// Yarn colouring benchmark: the fewest colours SolveColoring finds for square nets, against the
// counting lower bound, and whether the result is proven optimal.
//
//   bench_color [--time S]   (per-case time limit, default 4 s)
//   bench_color --scale [--time S]   (time and peak memory against net size)
//
// Cases: 6, 11, 17, 26 and 51 knots square; rules set, multiset, cyclic; min_distance 1 and 2;
// radius 0 (whole net); adjacency off, plus set / D = 1 and multiset / D = 2 with adjacency on,
// and set / D = 1 and 2 with uniqueness only within 3 links (tracking supplies the rest). Every
// result is checked by VerifyColoring (a failure is printed in the table, never hidden).

#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstring>
#include <string>

#include "libreconstruct/coloring/net_coloring.h"

namespace {

using namespace netlab::recon;

// One case in a child process of its own, so that its peak resident memory (wait4's ru_maxrss)
// is its own: solve, verify, and print a table row.
void ScaleCase(int n, CodeRule rule, int d, int radius, double time_s) {
  ColoringOptions o;
  o.rule = rule;
  o.min_distance = d;
  o.radius = radius;
  o.time_limit_s = time_s;
  std::fflush(stdout);
  const pid_t child = fork();
  if (child == 0) {
    const auto t0 = std::chrono::steady_clock::now();
    const NetColoring result = SolveColoring(n, n, o);
    const double solve_s = result.wall_s;
    std::string why;
    const bool ok = result.colors > 0 && VerifyColoring(result, &why);
    const double verify_s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() - solve_s;
    std::printf("| %dx%d | %s | %d | %d | %d | %d | %s | %.2f | %.2f | %s | %.0f |", n, n,
                CodeRuleName(rule).c_str(), d, radius, result.colors, result.lower_bound,
                result.time_limited ? "yes" : "no", solve_s, verify_s,
                result.colors == 0 ? "-"
                : ok               ? "yes"
                                   : "NO",
                EstimateColoringBytes(n, n, o) / 1e6);
    std::fflush(stdout);
    _exit(0);
  }
  int status = 0;
  rusage usage{};
  wait4(child, &status, 0, &usage);
  std::printf(" %.0f |\n", usage.ru_maxrss / 1024.0);  // kB -> MB (MiB-ish, as the kernel counts)
}

void Scale(double time_s) {
  std::printf("Per-case time limit %.0f s; each case in its own process.\n\n", time_s);
  std::printf(
      "| knots | rule | D | radius | colours | lower bound | time-limited | solve (s) | "
      "verify (s) | verified | estimate (MB) | peak RSS (MB) |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  for (int n : {100, 300, 1000}) {
    ScaleCase(n, CodeRule::kCyclic, 1, 0, time_s);
    ScaleCase(n, CodeRule::kCyclic, 2, 0, time_s);
    ScaleCase(n, CodeRule::kSet, 1, 3, time_s);
  }
}

}  // namespace

int main(int argc, char** argv) {
  double time_s = 4.0;
  bool scale = false;
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--time") == 0 && i + 1 < argc) time_s = std::atof(argv[++i]);
    if (std::strcmp(argv[i], "--scale") == 0) scale = true;
  }
  if (scale) {
    Scale(time_s);
    return 0;
  }
  std::printf("Per-case time limit %.1f s.\n\n", time_s);
  std::printf(
      "| knots | rule | D | adjacent distinct | radius | colours | lower bound | optimal | "
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
