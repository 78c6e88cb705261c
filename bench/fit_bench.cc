// bench_fit: `netlab fit` on the digital twin, where the truth is known.
//
//   bench_fit coverage [draws]   a small shot (5 x 5 knots, 0.4 s), 1 mm of noise, `draws` seeds
//                                (default 40); drag, launch velocity and time from a start off by
//                                2: how often the truth lands within 1 and 2 reported sigmas
//                                (68 % and 95 % when the sigmas are honest), simulations, time
//   bench_fit shots [draws]      the shot at 0.5, 0.8, 0.3 and 1.0 m/s, fitted 1, 2 and 4 at a
//                                time (one drag, each shot's launch and time; default 20 draws):
//                                the drag's error and sigma as shots are added
//   bench_fit flight [seconds] [shots] [implicit|explicit] [segments] [truth's segments] [prior]
//                                scenarios/net_a_0.5.yaml (then net_a_0.8, net_b_0.5, net_b_0.8
//                                for 2 or 4 shots) cut to `seconds` (default 2) of flight, 1 mm of
//                                noise; drag, EA and EI shared, each shot's launch velocity and
//                                time, from off by 2: error and sigma per parameter, simulations,
//                                wall time; with the scenarios' implicit integrator or the
//                                explicit one (truth and fit); the fit's and the truth's segments
//                                per link (0: the scenario's): a truth finer than the fit stands
//                                for a world the model does not resolve; prior: a bench prior on
//                                EA and EI with that relative spread (0.05: 5 %), EA 0.8 of it
//                                low and EI 0.8 of it high, the stiffnesses started there
//   bench_fit landscape [path] [truth] [seconds] [dt] [implicit|explicit]
//                                the cost along one material parameter (default the bend
//                                stiffness, 9.82e-5) of net_a_0.5 scaled x0.5 .. x2, for 4
//                                horizons up to `seconds`; dt: the step of every run (0: the
//                                truth's; default: automatic)
//
// Prints tables; never fails on time.

#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>
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
  const auto dir =
      std::filesystem::temp_directory_path() / ("bench_fit_" + std::to_string(getpid()));
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
    std::printf("| %s | %.3g | %.3g | %.0f %% | %.0f %% |\n", name.c_str(), sigma_sum[name] / draws,
                std::sqrt(error_sq[name] / draws), 100.0 * within1[name] / draws,
                100.0 * within2[name] / draws);
  std::printf("simulations per fit %.1f, wall per fit %.3f s\n", sims / draws, wall / draws);
  return 0;
}

// 1, 2 and 4 shots of the twin at 0.5, 0.8, 0.3 and 1.0 m/s, fitted together: the shared drag's
// error and sigma as shots are added, over `draws` noise draws.
int Shots(int draws) {
  const auto dir =
      std::filesystem::temp_directory_path() / ("bench_fit_shots_" + std::to_string(getpid()));
  std::filesystem::create_directories(dir);
  const char* speeds[4] = {"0.5", "0.8", "0.3", "1.0"};
  std::vector<std::string> paths;
  std::vector<SweepRun> truths;
  for (const char* speed : speeds) {
    std::string text = testing::kTwinShot;
    text.replace(text.find("velocity: [0.5, 0, 0]"), 21,
                 std::string("velocity: [") + speed + ", 0, 0]");
    paths.push_back((dir / (std::string("shot_") + speed + ".yaml")).string());
    std::ofstream(paths.back()) << text;
    truths.push_back(RunOne(paths.back(), 0, {}, 1));
  }
  const std::vector<ScenarioOverride> start = {{"drag.drag_coefficient", "2.4"}};
  std::printf(
      "shots: the twin (5 x 5 knots, 0.4 s) at 0.5, 0.8, 0.3, 1.0 m/s, 1 mm noise, %d "
      "draws; free: the drag (shared), each shot's launch velocity and time offset\n",
      draws);
  std::printf(
      "| shots | drag RMS error | drag mean sigma | within 2 sigma | simulations | "
      "wall per fit |\n|---|---|---|---|---|---|\n");
  for (int n : {1, 2, 4}) {
    const std::vector<std::string> used(paths.begin(), paths.begin() + n);
    const auto parameters =
        ParseFreeParameters("drag.drag_coefficient,nets.0.velocity,time_offset", used, start, 0);
    double error_sq = 0, sigma = 0, sims = 0, wall = 0;
    int within = 0;
    for (int d = 0; d < draws; ++d) {
      std::vector<KnotTracks> measured;
      for (int k = 0; k < n; ++k)
        measured.push_back(testing::MeasuredTwin(truths[k], 1e-3, 1000 * d + k));
      std::vector<FitShotInput> shots;
      for (int k = 0; k < n; ++k) shots.push_back({used[k], &measured[k], "shot"});
      const FitResult r = FitShots(shots, parameters, Options(start, 1e-3));
      const FittedParameter& drag = r.parameters.front();
      error_sq += (drag.value - 1.2) * (drag.value - 1.2);
      sigma += drag.sigma;
      within += std::abs(drag.value - 1.2) <= 2 * drag.sigma;
      sims += r.simulations;
      wall += r.wall_s;
    }
    std::printf("| %d | %.4f (%.2f %%) | %.4f | %.0f %% | %.0f | %.2f s |\n", n,
                std::sqrt(error_sq / draws), 100 * std::sqrt(error_sq / draws) / 1.2, sigma / draws,
                100.0 * within / draws, sims / draws, wall / draws);
  }
  std::filesystem::remove_all(dir);
  return 0;
}

// Why a parameter is not identified beyond its sigma, for the table.
std::string Note(const FittedParameter& p) {
  if (p.rough) return " (rough)";
  if (!p.ambiguous) return "";
  if (std::isnan(p.alternative)) return " (two valleys)";
  char text[96];
  std::snprintf(text, sizeof text, " (two valleys; the other's end: %.4g)", p.alternative);
  return text;
}

// The flight cases cut to `seconds`, 1 mm of noise, fitted `shots` at a time (net_a_0.5,
// net_a_0.8, net_b_0.5, net_b_0.8 in that order): drag, EA and EI shared, each shot's launch
// velocity and time; from drag x2, velocity x1/2, EA x2 and EI x1/2, or with a prior of relative
// spread `prior` (> 0), from the prior's values.
int Flight(double seconds, int shots, const std::string& integrator, int segments,
           int truth_segments, double prior) {
  const char* cases[4] = {"net_a_0.5", "net_a_0.8", "net_b_0.5", "net_b_0.8"};
  const double speeds[4] = {0.5, 0.8, 0.5, 0.8};
  char duration[32];
  std::snprintf(duration, sizeof duration, "%.17g", seconds);
  std::vector<std::string> paths;
  std::vector<KnotTracks> measured;
  std::map<std::string, double> truth_of = {{"drag.drag_coefficient", 1.2},
                                            {"materials.nylon_1mm.stretch_stiffness", 1571},
                                            {"materials.nylon_1mm.bend_stiffness", 9.82e-5}};
  for (int k = 0; k < shots; ++k) {
    paths.push_back(std::string(NETLAB_SOURCE_DIR) + "/scenarios/" + cases[k] + ".yaml");
    std::vector<ScenarioOverride> truth_set = {{"duration", duration},
                                               {"integrator.type", integrator}};
    if (truth_segments > 0)
      truth_set.push_back({"nets.0.segments_per_link", std::to_string(truth_segments)});
    const SweepRun truth = RunOne(paths.back(), 0, truth_set, 1);
    if (!truth.ok()) {
      std::fprintf(stderr, "the truth of %s failed: %s\n", cases[k], truth.error.c_str());
      return 1;
    }
    measured.push_back(testing::MeasuredTwin(truth, 1e-3, 7 + k));
    const std::string prefix = shots > 1 ? std::to_string(k + 1) + ":" : "";
    truth_of[prefix + "nets.0.velocity.0"] = speeds[k];
    truth_of[prefix + "nets.0.velocity.1"] = truth_of[prefix + "nets.0.velocity.2"] = 0.0;
    truth_of[prefix + "time_offset"] = 0.0;
  }
  // The launch is each scenario's own: started at half its speed by a --set per shot is not
  // possible (--set is shared), so the shared start moves every shot to 0.25 m/s.
  std::vector<ScenarioOverride> start = {{"integrator.type", integrator},
                                         {"drag.drag_coefficient", "2.4"},
                                         {"nets.0.velocity", "[0.25, 0, 0]"},
                                         {"materials.nylon_1mm.stretch_stiffness", "3142"},
                                         {"materials.nylon_1mm.bend_stiffness", "4.91e-5"}};
  if (segments > 0) start.push_back({"nets.0.segments_per_link", std::to_string(segments)});
  // A bench's prior, off the truth by 0.8 of its spread: EA low, EI high (as a tensile test that
  // reads soft and a cantilever that reads stiff).
  std::vector<FitPrior> priors;
  if (prior > 0) {
    for (const auto& [name, sign] :
         {std::pair<std::string, double>{"stretch_stiffness", -1.0}, {"bend_stiffness", 1.0}}) {
      const std::string path = "materials.nylon_1mm." + name;
      const double value = truth_of.at(path) * (1 + sign * 0.8 * prior);
      priors.push_back({path, value, prior * value, "a bench's prior"});
      char text[32];
      std::snprintf(text, sizeof text, "%.17g", value);
      start.push_back({path, text});
    }
  }
  const auto parameters = ParseFreeParameters(
      "drag.drag_coefficient,nets.0.velocity,time_offset,materials.nylon_1mm.stretch_stiffness,"
      "materials.nylon_1mm.bend_stiffness",
      paths, start, 0);
  std::vector<FitShotInput> inputs;
  for (int k = 0; k < shots; ++k) inputs.push_back({paths[k], &measured[k], cases[k]});
  FitOptions options = Options(start, 1e-3);
  options.priors = priors;
  options.progress = ProgressReporter([](const Progress& p) {
    std::fprintf(stderr, "  %s, %s, %.0f of at most %.0f simulations\n", p.stage.c_str(),
                 p.detail.c_str(), p.done, p.total);
  });
  const FitResult r = FitShots(inputs, parameters, options);
  std::printf("flight: %d shot%s (", shots, shots > 1 ? "s" : "");
  for (int k = 0; k < shots; ++k) std::printf("%s%s", k ? ", " : "", cases[k]);
  std::printf("), %.1f s each, %s, segments per link %s (truth's %s), 1 mm noise, start off by 2\n",
              seconds, integrator.c_str(),
              segments > 0 ? std::to_string(segments).c_str() : "the scenario's",
              truth_segments > 0 ? std::to_string(truth_segments).c_str() : "the scenario's");
  for (const FitPrior& p : priors)
    std::printf("prior: %s %.4g +- %.3g (%.0f %%), the start\n", p.name.c_str(), p.value, p.sigma,
                100 * prior);
  for (const std::string& note : r.notes) std::printf("note: %s\n", note.c_str());
  std::printf(
      "| parameter | truth | fitted | sigma | error / sigma | check -/+ 2 sigma | "
      "determined by |\n");
  std::printf("|---|---|---|---|---|---|---|\n");
  for (const FittedParameter& p : r.parameters) {
    const double t = truth_of.at(p.parameter.name);
    std::printf("| %s | %.4g | %.4g | %.3g | %.2f | %.2f / %.2f | %s%s |\n",
                p.parameter.name.c_str(), t, p.value, p.sigma, (p.value - t) / p.sigma, p.check[0],
                p.check[1], netsim::DeterminedByName(p.determined_by).c_str(), Note(p).c_str());
  }
  std::printf(
      "cost %.4g -> %.4g (%d residuals), %d simulations, %d iterations, %d ends, %.1f s wall\n",
      r.cost_initial, r.cost_final, r.residuals, r.simulations, r.iterations, r.ends, r.wall_s);
  return 0;
}

// The cost along one material parameter: chi^2 = sum d2 of net_a_0.5 with the parameter scaled by
// f against the truth's knots plus 1 mm of noise, for the horizons seconds/4, /2, 3/4 and
// seconds. Where the fit's cost is smooth enough for Levenberg-Marquardt, and from how far.
int Landscape(const std::string& parameter, double truth_value, double seconds, double fixed_dt,
              const std::string& integrator) {
  const std::string path = std::string(NETLAB_SOURCE_DIR) + "/scenarios/net_a_0.5.yaml";
  char duration[32];
  std::snprintf(duration, sizeof duration, "%.17g", seconds);
  const SweepRun truth =
      RunOne(path, 0, {{"duration", duration}, {"integrator.type", integrator}}, 1);
  if (!truth.ok()) return 1;
  const KnotTracks measured = testing::MeasuredTwin(truth, 1e-3, 7);
  char dt[32];
  std::snprintf(dt, sizeof dt, "%.17g", fixed_dt > 0 ? fixed_dt : truth.summary.dt);
  std::vector<double> horizons;
  for (int q = 1; q <= 4; ++q) horizons.push_back(seconds * q / 4);
  std::printf(
      "landscape of %s (truth %.4g) on net_a_0.5, 1 mm noise, %s, dt %s: chi^2 - 3 N per "
      "horizon\n",
      parameter.c_str(), truth_value, integrator.c_str(), fixed_dt >= 0 ? dt : "auto");
  std::printf("| factor |");
  for (double h : horizons) std::printf(" %.2f s |", h);
  std::printf("\n|---|");
  for (size_t i = 0; i < horizons.size(); ++i) std::printf("---|");
  std::printf("\n");
  for (int i = -8; i <= 8; ++i) {
    const double f = std::pow(2.0, i / 8.0);
    char value[32];
    std::snprintf(value, sizeof value, "%.17g", truth_value * f);
    std::vector<ScenarioOverride> set = {
        {"duration", duration}, {"integrator.type", integrator}, {parameter, value}};
    if (fixed_dt >= 0) set.push_back({"integrator.dt", dt});
    const SweepRun run = RunOne(path, 0, set, 1);
    std::printf("| %.3f |", f);
    for (double h : horizons) {
      if (!run.ok()) {
        std::printf(" failed |");
        continue;
      }
      KnotTracks cut = measured;
      int frames = 0;
      while (frames < static_cast<int>(cut.time.size()) && cut.time[frames] <= h + 1e-9) ++frames;
      const size_t n = static_cast<size_t>(frames) * cut.knots();
      cut.time.resize(frames);
      cut.position.resize(n);
      cut.valid.resize(n);
      if (!cut.covariance.empty()) cut.covariance.resize(n);
      if (!cut.frame_index.empty()) cut.frame_index.resize(frames);
      ScoreOptions o;
      o.meas_sigma_m = 1e-3;
      const ScoreSummary s = Score(cut, run.Tracks(), o).summary;
      std::printf(" %.4g |", s.mean_d2 * s.points - 3.0 * s.points);
    }
    std::printf("\n");
    std::fflush(stdout);
  }
  return 0;
}

}  // namespace
}  // namespace netlab::netsim

int main(int argc, char** argv) {
  const std::string what = argc > 1 ? argv[1] : "coverage";
  if (what == "coverage") return netlab::netsim::Coverage(argc > 2 ? std::atoi(argv[2]) : 40);
  if (what == "flight")
    return netlab::netsim::Flight(
        argc > 2 ? std::atof(argv[2]) : 2.0, argc > 3 ? std::atoi(argv[3]) : 1,
        argc > 4 ? argv[4] : "implicit", argc > 5 ? std::atoi(argv[5]) : 0,
        argc > 6 ? std::atoi(argv[6]) : 0, argc > 7 ? std::atof(argv[7]) : 0.0);
  if (what == "landscape")
    return netlab::netsim::Landscape(
        argc > 2 ? argv[2] : "materials.nylon_1mm.bend_stiffness",
        argc > 3 ? std::atof(argv[3]) : 9.82e-5, argc > 4 ? std::atof(argv[4]) : 2.0,
        argc > 5 ? std::atof(argv[5]) : -1.0, argc > 6 ? argv[6] : "implicit");
  if (what == "shots") return netlab::netsim::Shots(argc > 2 ? std::atoi(argv[2]) : 20);
  std::fprintf(
      stderr,
      "usage: bench_fit coverage [draws] | flight [seconds] [shots] [integrator] [segments] "
      "[truth's segments] [prior] | "
      "shots [draws] | landscape [path] [truth] [seconds] [dt] [integrator]\n");
  return 2;
}
