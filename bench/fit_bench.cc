// bench_fit: `netlab fit` on the digital twin, where the truth is known.
//
//   bench_fit coverage [draws]   a small shot (5 x 5 knots, 0.4 s), 1 mm of noise, `draws` seeds
//                                (default 40); drag, launch velocity and time from a start off by
//                                2: how often the truth lands within 1 and 2 reported sigmas
//                                (68 % and 95 % when the sigmas are honest), simulations, time
//   bench_fit flight [seconds]   scenarios/net_a_0.5.yaml cut to `seconds` (default 2) of flight,
//                                1 mm of noise; drag, launch velocity, time, EA and EI from off by
//                                2: relative error and sigma per parameter, simulations, wall time
//
// Prints tables; never fails on time.

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>
#include <unistd.h>
#include <vector>

#include "libnetsim/identification/shot_fit.h"
#include "libnetsim/sweep/sweep_runner.h"
#include "tests/libnetsim/identification/twin_shot.h"

namespace netlab::netsim {
namespace {

FitOptions Options(std::vector<ScenarioOverride> set, double sigma) {
  FitOptions o;
  o.set = std::move(set);
  o.score.meas_sigma_m = sigma;
  return o;
}

int Coverage(int draws) {
  const auto dir = std::filesystem::temp_directory_path() / ("bench_fit_" + std::to_string(getpid()));
  std::filesystem::create_directories(dir);
  const std::string scenario = (dir / "shot.yaml").string();
  std::ofstream(scenario) << testing::kTwinShot;
  const SweepRun truth = RunOne(scenario, 0, {}, 1);
  const std::vector<ScenarioOverride> start = {{"drag.drag_coefficient", "2.4"},
                                               {"nets.0.velocity", "[0.25, 0, 0]"}};
  const auto parameters =
      ParseFreeParameters("drag.drag_coefficient,nets.0.velocity,time_offset", scenario, start, 0);
  const std::map<std::string, double> truth_of = {{"drag.drag_coefficient", 1.2},
                                                  {"nets.0.velocity.0", 0.5},
                                                  {"nets.0.velocity.1", 0.0},
                                                  {"nets.0.velocity.2", 0.0},
                                                  {"time_offset", 0.0}};
  std::map<std::string, int> within1, within2;
  std::map<std::string, double> sigma_sum, error_sq;
  double sims = 0, wall = 0;
  for (int d = 0; d < draws; ++d) {
    const FitResult r = FitShot(scenario, testing::MeasuredTwin(truth, 1e-3, 100 + d), parameters,
                                Options(start, 1e-3));
    sims += r.simulations;
    wall += r.wall_s;
    for (const FittedParameter& p : r.parameters) {
      const double e = p.value - truth_of.at(p.parameter.name);
      within1[p.parameter.name] += std::abs(e) <= p.sigma;
      within2[p.parameter.name] += std::abs(e) <= 2 * p.sigma;
      sigma_sum[p.parameter.name] += p.sigma;
      error_sq[p.parameter.name] += e * e;
    }
  }
  std::filesystem::remove_all(dir);
  std::printf("coverage: %d noise draws (1 mm), 5 x 5 knots, 0.4 s, start off by 2\n", draws);
  std::printf("| parameter | mean sigma | RMS error | within 1 sigma | within 2 sigma |\n");
  std::printf("|---|---|---|---|---|\n");
  for (const auto& [name, truth_value] : truth_of)
    std::printf("| %s | %.3g | %.3g | %.0f %% | %.0f %% |\n", name.c_str(),
                sigma_sum[name] / draws, std::sqrt(error_sq[name] / draws),
                100.0 * within1[name] / draws, 100.0 * within2[name] / draws);
  std::printf("simulations per fit %.1f, wall per fit %.3f s\n", sims / draws, wall / draws);
  return 0;
}

int Flight(double seconds) {
  const std::string scenario = std::string(NETLAB_SOURCE_DIR) + "/scenarios/net_a_0.5.yaml";
  char duration[32];
  std::snprintf(duration, sizeof duration, "%.17g", seconds);
  const SweepRun truth = RunOne(scenario, 0, {{"duration", duration}}, 1);
  if (!truth.ok()) {
    std::fprintf(stderr, "the truth failed: %s\n", truth.error.c_str());
    return 1;
  }
  const std::vector<ScenarioOverride> start = {
      {"drag.drag_coefficient", "2.4"},
      {"nets.0.velocity", "[0.25, 0, 0]"},
      {"materials.nylon_1mm.stretch_stiffness", "3142"},
      {"materials.nylon_1mm.bend_stiffness", "4.91e-5"}};
  const auto parameters = ParseFreeParameters(
      "drag.drag_coefficient,nets.0.velocity,time_offset,materials.nylon_1mm.stretch_stiffness,"
      "materials.nylon_1mm.bend_stiffness",
      scenario, start, 0);
  const std::map<std::string, double> truth_of = {
      {"drag.drag_coefficient", 1.2}, {"nets.0.velocity.0", 0.5}, {"nets.0.velocity.1", 0.0},
      {"nets.0.velocity.2", 0.0},     {"time_offset", 0.0},
      {"materials.nylon_1mm.stretch_stiffness", 1571},
      {"materials.nylon_1mm.bend_stiffness", 9.82e-5}};
  FitOptions options = Options(start, 1e-3);
  const FitResult r = FitShot(scenario, testing::MeasuredTwin(truth, 1e-3, 7), parameters, options);
  std::printf("flight: Net A at 0.5 m/s, %.1f s, 121 knots, 1 mm noise, start off by 2\n",
              seconds);
  std::printf("| parameter | truth | fitted | sigma | error / sigma | check -/+ sigma | "
              "determined by |\n");
  std::printf("|---|---|---|---|---|---|---|\n");
  for (const FittedParameter& p : r.parameters) {
    const double t = truth_of.at(p.parameter.name);
    std::printf("| %s | %.4g | %.4g | %.3g | %.2f | %.2f / %.2f | %s%s |\n",
                p.parameter.name.c_str(), t, p.value, p.sigma, (p.value - t) / p.sigma,
                p.check[0], p.check[1], p.determined_by.c_str(), p.rough ? " (rough)" : "");
  }
  std::printf("cost %.4g -> %.4g (%d residuals), mean d2 %.3f, %d simulations, %d iterations, "
              "%.1f s wall\n",
              r.cost_initial, r.cost_final, r.residuals, r.score.mean_d2, r.simulations,
              r.iterations, r.wall_s);
  return 0;
}

}  // namespace
}  // namespace netlab::netsim

int main(int argc, char** argv) {
  const std::string what = argc > 1 ? argv[1] : "coverage";
  if (what == "coverage") return netlab::netsim::Coverage(argc > 2 ? std::atoi(argv[2]) : 40);
  if (what == "flight") return netlab::netsim::Flight(argc > 2 ? std::atof(argv[2]) : 2.0);
  std::fprintf(stderr, "usage: bench_fit coverage [draws] | flight [seconds]\n");
  return 2;
}
