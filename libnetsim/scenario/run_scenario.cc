#include "libnetsim/scenario/run_scenario.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iomanip>
#include <limits>
#include <memory>
#include <sstream>

#include "common/errors.h"
#include "common/memory.h"
#include "common/tracks/track_file.h"

namespace netlab::netsim {

std::string RunSummary::BriefReport() const {
  std::ostringstream os;
  os << std::setprecision(4);
  os << "scenario " << scenario << ": " << (stable ? "stable" : "UNSTABLE") << "\n";
  os << "  model       " << nodes << " nodes, " << segments << " segments, " << knots << " knots\n";
  os << "  forces      ";
  for (size_t i = 0; i < active.size(); ++i) os << (i ? ", " : "") << active[i];
  os << "\n";
  os << "  integrator  " << integrator << ", dt " << dt << " s (stability limit " << dt_limit
     << " s, rotational inertia scaled up to x" << max_inertia_scale << ")\n";
  os << "  run         " << steps << " steps";
  if (substeps > steps)
    os << " (split into " << substeps << " substeps, up to " << max_substeps
       << " in a step, where the tension needed them)";
  os << " to t = " << sim_time << " s in " << wall_s << " s wall: " << segment_steps_per_s / 1e6
     << " M segment-steps/s, " << real_time_factor << " x real time\n";
  if (!max_penetration_at.empty())
    os << "  contact     from t = " << contact_start_s << " s; deepest penetration "
       << max_penetration * 1e3 << " mm at " << max_penetration_at << "\n";
  os << "  energy      kinetic " << energy.kinetic << " J, elastic " << energy.elastic
     << " J, potential " << energy.potential << " J\n";
  for (const auto& [name, p] : probes)
    os << "  probe       " << name << " at (" << p.x() << ", " << p.y() << ", " << p.z() << ") m\n";
  if (!output.empty()) os << "  output      " << frames << " frames in " << output << "\n";
  if (!error.empty()) os << "  error       " << error << "\n";
  return os.str();
}

namespace {

// Throws InputError when the run's output frames cannot fit where they go (see RunScenario).
void CheckOutputSize(const Scenario& scenario, const RunOptions& options, double dt, int nodes,
                     int knots, int probes) {
  namespace fs = std::filesystem;
  // As the run counts them: a frame every steps_per_frame steps, and the first one.
  const double steps = scenario.duration / dt;
  const double steps_per_frame = std::max(1.0, std::round(scenario.output_interval / dt));
  const double frames = std::floor(steps / steps_per_frame) + 1.0;
  std::ostringstream head;
  head << std::setprecision(3)
       << (scenario.source_path.empty() ? scenario.name : scenario.source_path)
       << ": output_interval " << scenario.output_interval << " s over duration "
       << scenario.duration << " s (a step of " << dt << " s) gives " << frames << " output frames";
  const char* advice =
      "; raise output_interval (the flight scenarios write one frame per "
      "camera frame, 1/179 s)";
  if (!options.out_path.empty()) {
    // /time, the knots (position and valid), the probes and, when stored, every node.
    const double per_frame =
        8.0 + knots * 25.0 + probes * 24.0 + (scenario.store_nodes ? nodes * 24.0 : 0.0);
    std::error_code error;
    fs::path folder = fs::absolute(options.out_path, error).parent_path();
    const fs::space_info space = fs::space(folder, error);
    if (!error && frames * per_frame > static_cast<double>(space.available)) {
      std::ostringstream os;
      os << head.str() << ": ~" << FormatBytes(frames * per_frame) << " in " << options.out_path
         << ", " << FormatBytes(static_cast<double>(space.available)) << " free there" << advice;
      throw InputError(os.str());
    }
  }
  if (options.keep_every > 0) {
    const double kept = std::ceil(frames / options.keep_every) * (8.0 + knots * 24.0);
    if (const std::string shortfall = MemoryShortfall(kept); !shortfall.empty()) {
      std::ostringstream os;
      os << head.str() << ": keeping their knot tracks in memory " << shortfall << advice;
      throw InputError(os.str());
    }
  }
}

}  // namespace

RunSummary RunScenario(const Scenario& scenario, const RunOptions& options) {
  BuiltScenario built = BuildScenario(scenario);
  if (options.on_built) options.on_built(built);
  Simulation& sim = *built.simulation;
  const Model& model = sim.model();

  RunSummary summary;
  summary.scenario = scenario.name;
  summary.integrator = IntegratorName(scenario.simulation.integrator);
  summary.dt = sim.dt();
  summary.dt_limit = sim.stability().dt_limit;
  summary.max_inertia_scale = sim.stability().max_inertia_scale;
  summary.nodes = model.num_nodes();
  summary.segments = model.num_segments();
  summary.knots = model.num_knots();
  summary.active = sim.active_forces();

  // The output sized before any step: an output_interval of 1e-12 s asks for a frame every step
  // of a step shrunk to it (the step divides the interval), 6e10 frames of a 0.06 s shot, and ran
  // for days filling the disk. Refused when the frames need more than the disk holds (a file) or
  // the memory (frames kept by on_frame), naming output_interval and the size.
  CheckOutputSize(scenario, options, sim.dt(), model.num_nodes(),
                  static_cast<int>(built.knot_nodes.size()),
                  static_cast<int>(built.probe_nodes.size()));
  // A step so small that the run could never end (a material 1e300 stiff gave dt = 6.5e-154 s,
  // and the step count overflowed into a run of 0 steps reported as stable) is refused up front.
  // 1e13 segment-steps is a week at the 15 M segment-steps/s of one core.
  const double steps_needed = scenario.duration / sim.dt();
  if (!(steps_needed * std::max(1, model.num_segments()) <= 1e13)) {
    std::ostringstream os;
    os << std::setprecision(3)
       << (scenario.source_path.empty() ? scenario.name : scenario.source_path) << ": dt "
       << sim.dt() << " s (stability limit " << sim.stability().dt_limit << " s";
    if (sim.stability().limiting_node >= 0)
      os << ", set by " << model.DescribeNode(sim.stability().limiting_node);
    os << ") would take " << steps_needed << " steps of " << model.num_segments()
       << " segments to reach duration " << scenario.duration
       << " s: check the materials' stiffness, damping and linear density (or integrator.dt)";
    // The step falls with the segments' length: name the key that made them short.
    int shortest = -1;
    for (size_t n = 0; n < scenario.nets.size(); ++n)
      if (shortest < 0 ||
          scenario.nets[n].mesh / scenario.nets[n].segments_per_link <
              scenario.nets[shortest].mesh / scenario.nets[shortest].segments_per_link)
        shortest = static_cast<int>(n);
    if (shortest >= 0 && scenario.nets[shortest].segments_per_link > 1) {
      const NetSpec& net = scenario.nets[shortest];
      os << ", and nets." << shortest << ".segments_per_link " << net.segments_per_link
         << " (segments of " << net.mesh / net.segments_per_link << " m)";
    }
    throw InputError(os.str());
  }
  // Output frames every `steps_per_frame` steps; an automatic dt divides the interval exactly.
  const long steps_per_frame = std::max(1L, std::lround(scenario.output_interval / sim.dt()));
  const long total_steps = std::lround(scenario.duration / sim.dt());
  // A step longer than the run (integrator.dt 10 s of a 0.01 s run) ran 0 steps and was
  // reported stable.
  if (total_steps < 1) {
    std::ostringstream os;
    os << std::setprecision(3)
       << (scenario.source_path.empty() ? scenario.name : scenario.source_path)
       << ": integrator.dt " << sim.dt() << " s is longer than the duration " << scenario.duration
       << " s: the run would take no step; shorten integrator.dt (or leave it auto)";
    throw InputError(os.str());
  }

  std::unique_ptr<TrackFileWriter> writer;
  if (!options.out_path.empty()) {
    TrackFileWriter::Layout layout;
    layout.nodes = scenario.store_nodes ? model.num_nodes() : 0;
    layout.grid = built.knot_grid;
    layout.net = built.knot_net;
    layout.net_names = built.net_names;
    layout.probe_names = built.probe_names;
    layout.scenario = scenario.text;
    writer = std::make_unique<TrackFileWriter>(options.out_path, layout);
  }
  std::vector<Vector3d> knots(built.knot_nodes.size()), probes(built.probe_nodes.size());
  auto write_frame = [&] {
    if (!writer && !options.on_frame) return;
    const State& s = sim.state();
    for (size_t k = 0; k < knots.size(); ++k) knots[k] = s.x[built.knot_nodes[k]];
    if (options.on_frame) options.on_frame(s.time, knots);
    if (!writer) return;
    for (size_t p = 0; p < probes.size(); ++p) probes[p] = s.x[built.probe_nodes[p]];
    writer->AppendFrame(s.time, s.x, knots, probes);
  };

  const auto start = std::chrono::steady_clock::now();
  write_frame();
  const long progress_every = std::max(1L, total_steps / 50);
  double contact_start = std::numeric_limits<double>::quiet_NaN();
  for (long step = 1; step <= total_steps; ++step) {
    if (options.progress.cancelled()) {
      const std::string partial = writer ? writer->partial_path() : "";
      writer.reset();  // closes the file before it goes
      if (!partial.empty()) std::remove(partial.c_str());
      throw Cancelled();
    }
    if (!sim.Step()) break;
    if (std::isnan(contact_start) && sim.max_penetration() > 0.0) {
      contact_start = sim.state().time;  // the first step that found a node inside a body
      if (writer) writer->SetContactStart(contact_start);
    }
    if (step % steps_per_frame == 0) write_frame();
    if (step % progress_every == 0) options.progress.Report("steps", step, total_steps);
  }
  summary.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  const State& s = sim.state();
  summary.steps = sim.steps_taken();
  summary.substeps = sim.substeps_taken();
  summary.max_substeps = sim.max_substeps();
  summary.sim_time = s.time;
  summary.segment_steps_per_s =
      summary.wall_s > 0.0 ? summary.segments * static_cast<double>(summary.steps) / summary.wall_s
                           : 0.0;
  summary.real_time_factor = summary.wall_s > 0.0 ? s.time / summary.wall_s : 0.0;
  summary.max_penetration = sim.max_penetration();
  summary.contact_start_s = contact_start;
  if (sim.max_penetration_node() >= 0)
    summary.max_penetration_at = model.DescribeNode(sim.max_penetration_node());
  for (size_t p = 0; p < built.probe_nodes.size(); ++p)
    summary.probes.emplace_back(built.probe_names[p], s.x[built.probe_nodes[p]]);
  summary.energy = sim.ComputeEnergy();
  if (writer) summary.frames = writer->frames();
  if (sim.failure()) {
    summary.stable = false;
    summary.error = sim.failure()->message;
    if (writer) summary.error += "; the frames up to the failure are in " + writer->partial_path();
  } else if (writer) {
    writer->Commit();
    summary.output = options.out_path;
  }
  return summary;
}

}  // namespace netlab::netsim
