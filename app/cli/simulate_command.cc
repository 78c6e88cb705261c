// netlab simulate SCENARIO.yaml --out result.h5 [--set PATH=VALUE ...] [--json] [--quiet]

#include <unistd.h>

#include <cstdio>
#include <exception>
#include <iostream>
#include <string>
#include <vector>

#include "app/cli/commands.h"
#include "app/cli/json_writer.h"
#include "app/cli/progress_bar.h"
#include "app/command_line/command_line.h"
#include "common/files.h"
#include "common/log.h"
#include "common/output_paths.h"
#include "libnetsim/scenario/run_scenario.h"
#include "libnetsim/scenario/scenario_override.h"

namespace netlab::app {
namespace {

constexpr char kHelp[] =
    "usage: netlab simulate SCENARIO.yaml --out RESULT.h5 [--set PATH=VALUE ...] [--duration S]\n"
    "                       [--json] [--quiet]\n\n"
    "Runs the Cosserat-rod simulation described by SCENARIO.yaml (docs/scenarios.md) and writes\n"
    "the knot-track file RESULT.h5 (/time, /nodes/position, /knots/position, /knots/grid,\n"
    "/knots/valid, /probes/<name>, /scenario). Progress goes to stderr.\n\n"
    "options:\n"
    "  --out FILE   output HDF5 file (written to FILE.partial, renamed when complete)\n"
    "  --json       print one JSON summary object on stdout as the last output\n"
    "  --duration S simulate S seconds instead of the scenario's duration\n"
    "  --set PATH=VALUE\n"
    "               change one value of the scenario, by its dotted path (repeatable):\n"
    "               integrator.dt=1e-5, materials.nylon_1mm.bend_stiffness=2e-4,\n"
    "               nets.0.velocity=[0.8,0,0], drag.drag_coefficient=1.0\n"
    "  --quiet      no progress on stderr\n\n"
    "exit status: 0 stable run, 1 bad scenario or blow-up (the error names time, node and\n"
    "quantity), 2 usage error.\n";

void PrintJson(const netsim::RunSummary& s) {
  JsonWriter json;
  json.BeginObject();
  json.Key("scenario").String(s.scenario);
  json.Key("stable").Bool(s.stable);
  if (!s.stable) json.Key("error").String(s.error);
  json.Key("integrator").String(s.integrator);
  json.Key("dt").Number(s.dt);
  json.Key("dt_limit").Number(s.dt_limit);
  json.Key("steps").Int(s.steps);
  json.Key("substeps").Int(s.substeps);
  json.Key("nodes").Int(s.nodes);
  json.Key("segments").Int(s.segments);
  json.Key("knots").Int(s.knots);
  json.Key("frames").Int(s.frames);
  json.Key("sim_time").Number(s.sim_time);
  json.Key("wall_s").Number(s.wall_s);
  json.Key("segment_steps_per_s").Number(s.segment_steps_per_s);
  json.Key("real_time_factor").Number(s.real_time_factor);
  json.Key("max_penetration").Number(s.max_penetration);
  json.Key("contact_start_s").Number(s.contact_start_s);
  json.Key("max_inertia_scale").Number(s.max_inertia_scale);
  json.Key("probes").BeginObject();
  for (const auto& [name, p] : s.probes) json.Key(name).Vector3(p);
  json.EndObject();
  json.Key("energy").BeginObject();
  json.Key("kinetic").Number(s.energy.kinetic);
  json.Key("elastic").Number(s.energy.elastic);
  json.Key("potential").Number(s.energy.potential);
  json.EndObject();
  json.Key("active").BeginArray();
  for (const std::string& a : s.active) json.String(a);
  json.EndArray();
  json.Key("output").String(s.output);
  json.EndObject();
  std::cout << json.str() << std::endl;
}

}  // namespace

int RunSimulate(const std::vector<std::string>& args) {
  return RunGuarded("simulate", [&] {
    const CommandLine cl(args, {"json", "quiet", "help"}, {"out", "duration", "set"});
    if (cl.Flag("help")) {
      std::fputs(kHelp, stdout);
      return 0;
    }
    if (cl.positional().size() != 1) throw UsageError("expected one SCENARIO.yaml");
    const std::string out = cl.Required("out");
    const std::vector<netsim::ScenarioOverride> overrides = cl.Overrides("set");
    CheckOutputPaths({{"scenario", cl.positional()[0]}}, {{"--out", out}});

    netsim::Scenario scenario = netsim::LoadScenario(cl.positional()[0], overrides);
    // A shorter (or longer) run of the same scene, e.g. the first second of a flight.
    scenario.duration = cl.DoubleOption("duration", scenario.duration, 1e-9, 1e6);
    netsim::RunOptions options;
    options.out_path = out;
    const bool quiet = cl.Flag("quiet");
    ProgressBar bar("simulate", !quiet);
    options.progress = bar.Reporter();
    // A run that throws (a full disk, Ctrl+C) leaves no partial file; one that blows up keeps its
    // frames up to the failure in OUT.partial (RunScenario names it), and OUT as it was.
    OutputSet outputs({out});
    const netsim::RunSummary summary = netsim::RunScenario(scenario, options);
    outputs.Commit();
    bar.Break();
    if (!quiet || !cl.Flag("json")) std::cerr << summary.BriefReport();
    if (!summary.stable) {
      NETLAB_LOG(kError) << summary.error;
    }
    if (cl.Flag("json")) PrintJson(summary);
    return summary.stable ? 0 : 1;
  });
}

}  // namespace netlab::app
