// Simulator benchmark: speed against error for the shipped scenarios.
//
//   bench_simulate [--quick] [--window SECONDS] [--dir SCENARIO_DIR] [CASE ...]
//   bench_simulate --threads N [--window SECONDS] [CASE ...]   one thread against N
//   bench_simulate --integrator implicit [--no-physical] [--substep-contact] [CASE ...]
//                                                                    another integrator
//   bench_simulate --sensitivity [--floor] [--keep-coupling] [--physical-inertia]
//                  [--parameter NAME ...] [--factor F] [--integrator NAME] [--stretching NAME]
//                  [--dt-factor F]
//                  [--window SECONDS] [CASE ...]
//   bench_simulate --add-noise SIGMA_M SEED IN.h5 OUT.h5
//                                   the knot tracks of IN (netlab simulate) plus Gaussian noise
//                                   of SIGMA_M per coordinate (seeded), /knots/covariance
//                                   SIGMA_M^2 I: the measured tracks of the digital-twin checks
//                                   (docs/simulator.md, "What it tells apart")
//
// --sensitivity (default cases Net A and Net B at 0.5 m/s, the first 1 s of flight): whether the
// scenario's integrator keeps the physics. For each material parameter of the flight nets (EA x0.5;
// EI, GJ, c_s, c_b, c_t x4; the drag coefficient C_d x1.5, changed in every material), the
// knots' response to the change (the changed run minus the nominal run, per knot and frame)
// under the scenario's integrator and under the explicit step at its own automatic step (the
// reference), and the relative error RMS(response - reference response) / RMS(reference
// response). --floor adds the reference floor: the same relative difference between the
// reference's response and that of the explicit step at half its step. --keep-coupling holds the
// coupling penalty (kappa = 100 max(EI, GJ) / l^2, a numerical device of the explicit model) at
// its nominal value when EI or GJ changes. --stretching sets the implicit integrator's stretching
// step (backward_euler, sdirk2) of the tested runs. --physical-inertia runs every one of them
// with the physical rotational inertia (the explicit step then set by the frames). --factor F
// changes every parameter by F instead of its own factor (F near 1: whether the flight
// amplifies a small change). Wall time and "x
// real time" are those of the changed run under the tested integrator, in process CPU time (one
// core, whatever the machine's load).
//
// Per case: the scenario's run (its integrator, automatic dt, rotational inertia scaled) with its
// segments, dt, steps, wall time, segment-steps/s and real-time factor; its error against a
// converged reference (twice the segments per rod or link, and a quarter of the step); and the
// error the rotational inertia scaling alone makes (same discretisation with the physical
// cross-section inertia and its much smaller step). Errors are RMS and max over the tracked
// points (knots of nets, the nodes of rods shared with the finer rod) and over output frames, in
// mm. The parabolic-flight
// cases run for a window (default 1 s) of their flight. The timed run is repeated (--repeat N,
// default 3) and the fastest kept: wall times on a shared machine vary by +-20 %. Prints a
// Markdown table. With --threads N: the default run on one thread and on N (the forces' loops
// split, SimulationOptions::threads), their wall times and whether every tracked point of every
// frame has the same bits. With --integrator NAME the timed run and the inertia-scaling run use
// that integrator (the reference stays explicit); --no-physical leaves the inertia-scaling run
// out (with implicit it keeps the frames explicit at their tiny step: minutes for Net B);
// --substep-contact resolves the implicit integrator's contact by substeps of the whole net
// (SimulationOptions::implicit_contact = false) instead of implicitly.

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <exception>
#include <random>
#include <string>
#include <vector>

#include "common/tracks/track_file.h"
#include "libnetsim/scenario/scenario.h"

namespace netlab::netsim {
namespace {

struct Trajectory {
  std::vector<std::vector<Vector3d>> frames;  // tracked points per output frame
  int segments = 0;
  double dt = 0.0;
  long steps = 0;
  double wall_s = 0.0;
  double cpu_s = 0.0;  // process CPU time of the run
  double sim_time = 0.0;
  bool stable = true;
};

// Runs `base` with every rod and link split `refine` times finer, the step scaled by
// `dt_factor` (1: automatic), and the physical or scaled rotational inertia.
Trajectory Run(Scenario s, double window, int refine, double dt_factor, bool physical,
               int threads = 1, const char* integrator = nullptr) {
  s.duration = std::min(s.duration, window);
  if (integrator) ParseIntegratorType(integrator, &s.simulation.integrator);
  s.simulation.threads = threads;
  for (RodSpec& r : s.rods) r.segments *= refine;
  for (NetSpec& n : s.nets) n.segments_per_link *= refine;
  s.simulation.scale_rotational_inertia = !physical;
  s.simulation.safety = s.simulation.EffectiveSafety() * dt_factor;
  BuiltScenario built = BuildScenario(s);
  Simulation& sim = *built.simulation;
  const Model& model = sim.model();

  // Tracked points: knots, or the rod nodes that coarse and fine rods share.
  std::vector<int> points = built.knot_nodes;
  for (const RodInfo& rod : model.rods)
    for (int i = 0; i < rod.num_nodes; i += refine) points.push_back(rod.first_node + i);

  Trajectory t;
  t.segments = model.num_segments();
  t.dt = sim.dt();
  const long per_frame = std::max(1L, std::lround(s.output_interval / sim.dt()));
  const long total = std::lround(s.duration / sim.dt());
  auto sample = [&] {
    std::vector<Vector3d> frame;
    for (int p : points) frame.push_back(sim.state().x[p]);
    t.frames.push_back(frame);
  };
  const auto start = std::chrono::steady_clock::now();
  const std::clock_t cpu_start = std::clock();
  sample();
  for (long k = 1; k <= total; ++k) {
    if (!sim.Step()) {
      t.stable = false;
      break;
    }
    if (k % per_frame == 0) sample();
  }
  t.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  t.cpu_s = static_cast<double>(std::clock() - cpu_start) / CLOCKS_PER_SEC;
  t.steps = sim.steps_taken();
  t.sim_time = sim.state().time;
  return t;
}

struct Error {
  double rms_mm = 0.0;
  double max_mm = 0.0;
};

Error Compare(const Trajectory& a, const Trajectory& b) {
  Error e;
  double sum = 0.0;
  long n = 0;
  const size_t frames = std::min(a.frames.size(), b.frames.size());
  for (size_t f = 0; f < frames; ++f)
    for (size_t p = 0; p < a.frames[f].size() && p < b.frames[f].size(); ++p) {
      const double d = (a.frames[f][p] - b.frames[f][p]).norm() * 1e3;
      sum += d * d;
      e.max_mm = std::max(e.max_mm, d);
      ++n;
    }
  e.rms_mm = n ? std::sqrt(sum / n) : 0.0;
  return e;
}

// One material or air parameter of the scene, changed by a factor in every material (or in the
// drag).
struct Parameter {
  const char* name;
  double factor;
  double Material::*field;  // null: the drag coefficient
};

constexpr Parameter kParameters[] = {{"EA", 0.5, &Material::stretch_stiffness},
                                     {"EI", 4.0, &Material::bend_stiffness},
                                     {"GJ", 4.0, &Material::twist_stiffness},
                                     {"c_s", 4.0, &Material::stretch_damping},
                                     {"c_b", 4.0, &Material::bend_damping},
                                     {"c_t", 4.0, &Material::twist_damping},
                                     {"C_d", 1.5, nullptr}};

Scenario Changed(Scenario s, const Parameter& p) {
  if (p.field) {
    for (Material& m : s.materials) m.*(p.field) *= p.factor;
  } else if (s.drag) {
    s.drag->drag_coefficient *= p.factor;
  }
  return s;
}

// Per tracked point and frame, the change b - a (m).
std::vector<std::vector<Vector3d>> Response(const Trajectory& a, const Trajectory& b) {
  std::vector<std::vector<Vector3d>> r;
  const size_t frames = std::min(a.frames.size(), b.frames.size());
  for (size_t f = 0; f < frames; ++f) {
    r.emplace_back();
    for (size_t p = 0; p < a.frames[f].size() && p < b.frames[f].size(); ++p)
      r.back().push_back(b.frames[f][p] - a.frames[f][p]);
  }
  return r;
}

double Rms(const std::vector<std::vector<Vector3d>>& r) {
  double sum = 0.0;
  long n = 0;
  for (const auto& frame : r)
    for (const Vector3d& d : frame) {
      sum += d.squaredNorm();
      ++n;
    }
  return n ? std::sqrt(sum / n) : 0.0;
}

// --sensitivity: per case and parameter, the knots' response to the parameter's change under the
// scenario's own integrator and under the explicit reference at its own step, and how far apart
// the two responses are.
int Sensitivity(const std::string& dir, const std::vector<std::string>& cases, double window,
                const char* integrator, const std::vector<std::string>& only, double dt_factor,
                bool with_floor, bool keep_coupling, const char* stretching, bool physical,
                double factor) {
  std::printf(
      "| case | parameter | factor | reference response RMS / max (mm) | %s response RMS / max "
      "(mm) | relative error | reference floor | %s CPU (s) | x real time | reference CPU (s) |\n"
      "|---|---|---|---|---|---|---|---|---|---|\n",
      integrator ? integrator : "default", integrator ? integrator : "default");
  std::fflush(stdout);
  for (const std::string& case_name : cases) {
    Scenario s = LoadScenario(dir + "/" + case_name + ".yaml");
    if (stretching && !ParseStretchingScheme(stretching, &s.simulation.stretching)) {
      std::fprintf(stderr, "--stretching: expected backward_euler or sdirk2, got '%s'\n",
                   stretching);
      return 2;
    }
    const double w = std::min(window, s.duration);
    const Trajectory ref = Run(s, w, 1, 1.0, physical, 1, "explicit");
    const Trajectory def = Run(s, w, 1, dt_factor, physical, 1, integrator);
    const Trajectory half = with_floor ? Run(s, w, 1, 0.5, physical, 1, "explicit") : Trajectory{};
    std::printf(
        "| %s | nominal | 1 | – | %.3f / %.3f from the reference | – | – | %.2f | %.2f | %.2f "
        "|%s\n",
        case_name.c_str(), Compare(def, ref).rms_mm, Compare(def, ref).max_mm, def.cpu_s,
        def.sim_time / def.cpu_s, ref.cpu_s, ref.stable && def.stable ? "" : " UNSTABLE");
    std::fflush(stdout);
    for (Parameter p : kParameters) {
      if (factor > 0.0) p.factor = factor;
      if (!only.empty() && std::find(only.begin(), only.end(), p.name) == only.end()) continue;
      Scenario changed = Changed(s, p);
      if (keep_coupling && !s.materials.empty()) {
        // The coupling penalty follows max(EI, GJ) (ModelBuilderOptions): held where it was.
        const Material& a = s.materials[0];
        const Material& b = changed.materials[0];
        changed.model.coupling_stiffness_ratio *= std::max(a.bend_stiffness, a.twist_stiffness) /
                                                  std::max(b.bend_stiffness, b.twist_stiffness);
      }
      const Trajectory ref_p = Run(changed, w, 1, 1.0, physical, 1, "explicit");
      const Trajectory def_p = Run(changed, w, 1, dt_factor, physical, 1, integrator);
      const auto r_ref = Response(ref, ref_p), r_def = Response(def, def_p);
      std::vector<std::vector<Vector3d>> diff = r_def;
      double max_ref = 0.0, max_def = 0.0;
      for (size_t f = 0; f < diff.size() && f < r_ref.size(); ++f)
        for (size_t k = 0; k < diff[f].size() && k < r_ref[f].size(); ++k) {
          diff[f][k] -= r_ref[f][k];
          max_ref = std::max(max_ref, r_ref[f][k].norm());
          max_def = std::max(max_def, r_def[f][k].norm());
        }
      const double rms_ref = Rms(r_ref);
      double floor = -1.0;
      if (with_floor) {
        const Trajectory half_p = Run(changed, w, 1, 0.5, physical, 1, "explicit");
        std::vector<std::vector<Vector3d>> d = Response(half, half_p);
        for (size_t f = 0; f < d.size() && f < r_ref.size(); ++f)
          for (size_t k = 0; k < d[f].size() && k < r_ref[f].size(); ++k) d[f][k] -= r_ref[f][k];
        floor = rms_ref > 0 ? Rms(d) / rms_ref : 0.0;
      }
      char floor_text[32] = "–";
      if (floor >= 0.0) std::snprintf(floor_text, sizeof floor_text, "%.2f", floor);
      std::printf(
          "| %s | %s | %g | %.3f / %.2f | %.3f / %.2f | %.2f | %s | %.2f | %.2f | %.2f |%s\n",
          case_name.c_str(), p.name, p.factor, rms_ref * 1e3, max_ref * 1e3, Rms(r_def) * 1e3,
          max_def * 1e3, rms_ref > 0 ? Rms(diff) / rms_ref : 0.0, floor_text, def_p.cpu_s,
          def_p.sim_time / def_p.cpu_s, ref_p.cpu_s,
          ref_p.stable && def_p.stable ? "" : " UNSTABLE");
      std::fflush(stdout);
    }
  }
  return 0;
}

// --add-noise: IN's knots plus N(0, sigma^2) per coordinate, covariance sigma^2 I, to OUT.
int AddNoise(double sigma, unsigned seed, const std::string& in, const std::string& out) {
  netlab::KnotTracks tracks = netlab::ReadKnotTracks(in);
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> noise(0.0, sigma);
  for (Vector3d& p : tracks.position) p += Vector3d(noise(rng), noise(rng), noise(rng));
  tracks.covariance.assign(tracks.position.size(), sigma * sigma * Eigen::Matrix3d::Identity());
  tracks.source = "bench_simulate --add-noise";
  netlab::WriteKnotTracks(out, tracks);
  std::printf("%s: %d frames x %d knots of %s plus %g m of noise (seed %u)\n", out.c_str(),
              tracks.frames(), tracks.knots(), in.c_str(), sigma, seed);
  return 0;
}

}  // namespace
}  // namespace netlab::netsim

int main(int argc, char** argv) {
  using namespace netlab::netsim;
  if (argc == 6 && !std::strcmp(argv[1], "--add-noise")) {
    const double sigma = std::atof(argv[2]);
    if (!(sigma > 0.0)) {
      std::fprintf(stderr, "bench_simulate --add-noise: SIGMA_M must be > 0 (m), got '%s'\n",
                   argv[2]);
      return 2;
    }
    try {
      return AddNoise(sigma, static_cast<unsigned>(std::strtoul(argv[3], nullptr, 10)), argv[4],
                      argv[5]);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "bench_simulate --add-noise: %s\n", e.what());
      return 1;
    }
  }
  std::string dir = std::string(NETLAB_SOURCE_DIR) + "/scenarios";
  double window = 1.0;
  bool quick = false;
  int repeat = 3;
  int threads = 0;
  const char* integrator = nullptr;
  const char* stretching = nullptr;
  bool physical_runs = true;
  bool substep_contact = false;
  bool sensitivity = false;
  bool floor = false;
  bool keep_coupling = false;
  bool physical_inertia = false;
  double factor = 0.0;
  double dt_factor = 1.0;
  std::vector<std::string> only;
  std::vector<std::string> cases;
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--quick")) {
      quick = true;
      window = 0.2;
    } else if (!std::strcmp(argv[i], "--window") && i + 1 < argc) {
      window = std::atof(argv[++i]);
    } else if (!std::strcmp(argv[i], "--repeat") && i + 1 < argc) {
      repeat = std::max(1, std::atoi(argv[++i]));
    } else if (!std::strcmp(argv[i], "--threads") && i + 1 < argc) {
      threads = std::max(1, std::atoi(argv[++i]));
    } else if (!std::strcmp(argv[i], "--substep-contact")) {
      substep_contact = true;
    } else if (!std::strcmp(argv[i], "--sensitivity")) {
      sensitivity = true;
    } else if (!std::strcmp(argv[i], "--keep-coupling")) {
      keep_coupling = true;
    } else if (!std::strcmp(argv[i], "--factor") && i + 1 < argc) {
      factor = std::atof(argv[++i]);
    } else if (!std::strcmp(argv[i], "--physical-inertia")) {
      physical_inertia = true;
    } else if (!std::strcmp(argv[i], "--stretching") && i + 1 < argc) {
      stretching = argv[++i];
    } else if (!std::strcmp(argv[i], "--floor")) {
      floor = true;
    } else if (!std::strcmp(argv[i], "--dt-factor") && i + 1 < argc) {
      dt_factor = std::atof(argv[++i]);
    } else if (!std::strcmp(argv[i], "--parameter") && i + 1 < argc) {
      only.push_back(argv[++i]);
    } else if (!std::strcmp(argv[i], "--no-physical")) {
      physical_runs = false;
    } else if (!std::strcmp(argv[i], "--integrator") && i + 1 < argc) {
      integrator = argv[++i];
    } else if (!std::strcmp(argv[i], "--dir") && i + 1 < argc) {
      dir = argv[++i];
    } else {
      cases.push_back(argv[i]);
    }
  }
  if (sensitivity) {
    if (cases.empty()) cases = {"net_a_0.5", "net_b_0.5"};
    return Sensitivity(dir, cases, window, integrator, only, dt_factor, floor, keep_coupling,
                       stretching, physical_inertia, factor);
  }
  if (cases.empty())
    cases = {"cantilever", "pendulum",  "net_capture", "net_a_0.5",
             "net_a_0.8",  "net_b_0.5", "net_b_0.8"};
  const auto fastest = [&](const Scenario& s, double w, int n) {
    Trajectory run = Run(s, w, 1, 1.0, false, n, integrator);
    for (int r = 1; r < repeat; ++r) {
      const Trajectory again = Run(s, w, 1, 1.0, false, n, integrator);
      if (again.wall_s < run.wall_s) run = again;
    }
    return run;
  };
  if (threads > 0) {
    std::printf(
        "| case | sim s | segments | wall, 1 thread (s) | wall, %d threads (s) | speed-up |"
        " x real time, %d threads | same bits |\n|---|---|---|---|---|---|---|---|\n",
        threads, threads);
    for (const std::string& case_name : cases) {
      const Scenario s = LoadScenario(dir + "/" + case_name + ".yaml");
      const double w = std::min(window, s.duration);
      const Trajectory one = fastest(s, w, 1), many = fastest(s, w, threads);
      const Error e = Compare(one, many);
      const bool same = e.max_mm == 0.0 && one.frames.size() == many.frames.size();
      std::printf("| %s | %.2f | %d | %.3f | %.3f | %.2f | %.2f | %s |\n", case_name.c_str(),
                  one.sim_time, one.segments, one.wall_s, many.wall_s, one.wall_s / many.wall_s,
                  many.sim_time / many.wall_s, same ? "yes" : "NO");
      std::fflush(stdout);
    }
    return 0;
  }
  std::printf(
      "| case | sim s | segments | dt (s) | steps | wall (s) | M seg-steps/s | x real time |"
      " error vs reference RMS / max (mm) | inertia-scaling error RMS / max (mm) |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|---|\n");
  for (const std::string& case_name : cases) {
    const char* name = case_name.c_str();
    Scenario s = LoadScenario(dir + "/" + case_name + ".yaml");
    s.simulation.implicit_contact = !substep_contact;
    const bool flight = case_name.rfind("net_", 0) == 0 && case_name != "net_capture";
    const double w = flight ? window : (quick ? std::min(window, s.duration) : s.duration);
    const Trajectory run = fastest(s, w, 1);
    const Trajectory reference = Run(s, w, 2, 0.5, false, 1, "explicit");  // a quarter of dt
    const Trajectory physical =
        physical_runs ? Run(s, w, 1, 1.0, true, 1, integrator) : Trajectory{};
    const Error e_ref = Compare(run, reference);
    const Error e_phys = Compare(run, physical);
    char physical_text[64] = "–";
    if (physical_runs)
      std::snprintf(physical_text, sizeof physical_text, "%.4f / %.4f", e_phys.rms_mm,
                    e_phys.max_mm);
    std::printf("| %s | %.2f | %d | %.3g | %ld | %.3f | %.1f | %.2f | %.3f / %.3f | %s |\n", name,
                run.sim_time, run.segments, run.dt, run.steps, run.wall_s,
                run.segments * run.steps / run.wall_s / 1e6, run.sim_time / run.wall_s,
                e_ref.rms_mm, e_ref.max_mm, physical_text);
    if (!run.stable || !reference.stable || !physical.stable)
      std::printf("| %s: a run was UNSTABLE |\n", name);
    std::fflush(stdout);
  }
  return 0;
}
