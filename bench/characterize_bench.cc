// bench_characterize: each bench test of `netlab characterize` simulated with libnetsim (the 1 mm
// Nylon thread, synthetic_bench.h) and fitted, over several noise seeds: the time to simulate and
// to fit, and each parameter's error relative to the truth and to its reported sigma. Prints a
// table; never fails on time.
//
//   build/bench/bench_characterize [--seeds N]

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <functional>
#include <map>
#include <string>

#include "libnetsim/characterization/characterize.h"
#include "libnetsim/characterization/synthetic_bench.h"

namespace {

using namespace netlab::netsim;

double Seconds(std::chrono::steady_clock::time_point since) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - since).count();
}

struct Row {
  double simulate_s = 0, fit_s = 0;
  std::map<std::string, std::pair<double, double>> error;  // key -> (mean |rel err|, mean |z|)
  std::map<std::string, double> bias;                      // key -> mean rel err
};

}  // namespace

int main(int argc, char** argv) {
  int seeds = 5;
  for (int i = 1; i + 1 < argc; ++i)
    if (!std::strcmp(argv[i], "--seeds")) seeds = std::atoi(argv[i + 1]);
  const Material truth = BenchNylon();
  const SyntheticWeighing weighing;
  const std::map<std::string, std::function<BenchTest(uint32_t)>> tests = {
      {"tensile", [&](uint32_t s) { return SimulateTensileTest(truth, {}, weighing, s); }},
      {"cantilever", [&](uint32_t s) { return SimulateCantileverTest(truth, {}, weighing, s); }},
      {"torsion", [&](uint32_t s) { return SimulateTorsionTest(truth, {}, weighing, s); }}};
  std::printf("bench_characterize: %d noise seeds per test, 1 mm Nylon (synthetic_bench.h)\n\n",
              seeds);
  std::printf("%-11s %-18s %10s %9s %10s %11s %12s %8s\n", "test", "parameter", "simulate_s",
              "fit_s", "mean err%", "mean|err|%", "mean sigma%", "mean|z|");
  for (const auto& [name, simulate] : tests) {
    Row row;
    std::map<std::string, double> sigma_sum;
    for (int s = 1; s <= seeds; ++s) {
      auto start = std::chrono::steady_clock::now();
      const BenchTest test = simulate(static_cast<uint32_t>(100 + s));
      row.simulate_s += Seconds(start) / seeds;
      start = std::chrono::steady_clock::now();
      const Characterization c = Characterize(test);
      row.fit_s += Seconds(start) / seeds;
      for (const ParameterEstimate& e : c.estimates) {
        const double want = MaterialValue(truth, e.key);
        row.error[e.key].first += std::abs(e.value / want - 1) / seeds;
        row.bias[e.key] += (e.value / want - 1) / seeds;
        row.error[e.key].second += std::abs(e.value - want) / e.sigma / seeds;
        sigma_sum[e.key] += e.sigma / want / seeds;
      }
    }
    for (const auto& [key, error] : row.error)
      std::printf("%-11s %-18s %10.2f %9.3f %10.3f %11.3f %12.3f %8.2f\n", name.c_str(),
                  key.c_str(), row.simulate_s, row.fit_s, 100 * row.bias[key], 100 * error.first,
                  100 * sigma_sum[key], error.second);
  }
  std::printf(
      "\nmean|z| = mean |estimate - truth| / sigma: about 0.8 when the sigmas are right.\n");
  return 0;
}
