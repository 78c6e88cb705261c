// Simulator benchmark: speed against error for the shipped scenarios.
//
//   bench_simulate [--quick] [--window SECONDS] [--dir SCENARIO_DIR] [CASE ...]
//   bench_simulate --threads N [--window SECONDS] [CASE ...]   one thread against N
//   bench_simulate --integrator implicit [--no-physical] [--substep-contact] [CASE ...]
//                                                                    another integrator
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

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "libnetsim/scenario/scenario.h"

namespace netlab::netsim {
namespace {

struct Trajectory {
  std::vector<std::vector<Vector3d>> frames;  // tracked points per output frame
  int segments = 0;
  double dt = 0.0;
  long steps = 0;
  double wall_s = 0.0;
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
  sample();
  for (long k = 1; k <= total; ++k) {
    if (!sim.Step()) {
      t.stable = false;
      break;
    }
    if (k % per_frame == 0) sample();
  }
  t.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
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

}  // namespace
}  // namespace netlab::netsim

int main(int argc, char** argv) {
  using namespace netlab::netsim;
  std::string dir = std::string(NETLAB_SOURCE_DIR) + "/scenarios";
  double window = 1.0;
  bool quick = false;
  int repeat = 3;
  int threads = 0;
  const char* integrator = nullptr;
  bool physical_runs = true;
  bool substep_contact = false;
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
  if (cases.empty())
    cases = {"cantilever", "pendulum", "net_capture", "net_a_0.5", "net_a_0.8", "net_b_0.5",
             "net_b_0.8"};
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
  std::printf("| case | sim s | segments | dt (s) | steps | wall (s) | M seg-steps/s | x real time |"
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
