// netlab sweep SCENARIO.yaml --vary PATH=a:b:n [--vary ...] --out sweep.h5 [--report sweep.html]
//              [--set PATH=VALUE ...] [--jobs N] [--decimate N] [--json] [--quiet]

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "app/cli/commands.h"
#include "app/cli/json_writer.h"
#include "app/cli/progress_bar.h"
#include "app/command_line/command_line.h"
#include "common/errors.h"
#include "common/files.h"
#include "common/output_paths.h"
#include "libnetsim/scenario/scenario_override.h"
#include "libnetsim/sweep/sweep_file.h"
#include "libnetsim/sweep/sweep_grid.h"
#include "libnetsim/sweep/sweep_mpi.h"
#include "libnetsim/sweep/sweep_report.h"
#include "libnetsim/sweep/sweep_runner.h"
#include "libnetsim/sweep/sweep_sensitivity.h"

namespace netlab::app {
namespace {

constexpr char kHelp[] =
    "usage: netlab sweep SCENARIO.yaml --vary PATH=a:b:n [--vary ...] --out SWEEP.h5\n"
    "                    [--report SWEEP.html] [--set PATH=VALUE ...] [--jobs N] [--decimate N]\n"
    "                    [--ensemble N] [--json] [--quiet]\n"
    "       mpirun -np N netlab sweep ...   (the runs spread over N processes)\n\n"
    "A sensitivity study: runs SCENARIO.yaml once per point of a grid of parameter values and\n"
    "writes every run's summary and knot tracks to SWEEP.h5 (docs/sweep.md). Each --vary names\n"
    "one value of the scenario by the dotted path of `simulate --set` and gives it n evenly\n"
    "spaced values from a to b; several --vary make the full grid. A run that blows up or whose\n"
    "value the scenario rejects is reported (stderr, the file, the JSON) and the others go on.\n"
    "Progress and an ETA go to stderr.\n\n"
    "options:\n"
    "  --vary PATH=a:b:n\n"
    "                   vary one value, n values from a to b (repeatable), e.g.\n"
    "                   materials.nylon_1mm.bend_stiffness=1e-4:4e-4:4,\n"
    "                   drag.drag_coefficient=0.8:1.2:3, nets.0.corner_mass=0.01:0.03:3;\n"
    "                   n = 1 runs the one value a\n"
    "  --out FILE       sweep.h5 (written to FILE.partial, renamed when complete)\n"
    "  --report FILE    also an HTML page (open it in a browser): each output against each\n"
    "                   parameter, and the sensitivities d ln(output)/d ln(parameter) (a\n"
    "                   central difference at the grid's centre, docs/sweep.md)\n"
    "  --set PATH=VALUE change a value in every run (repeatable), e.g. --set duration=0.5\n"
    "  --jobs N         runs at a time in this process (threads; default: the machine's cores,\n"
    "                   1 per rank under mpirun)\n"
    "  --ensemble N     N runs instead of the full grid, each --vary at one of its n values\n"
    "                   (each value equally often, in a shuffled order with a fixed seed):\n"
    "                   runs differing only in what the model cannot know (the step, the\n"
    "                   links' resolution, the launch), for netlab score --sim-ensemble\n"
    "  --decimate N     keep every N-th output frame of each run's tracks (default 1: all)\n"
    "  --json           print one JSON summary object on stdout as the last output: runs, ok,\n"
    "                   failed, wall_s, runs_per_hour, parameters, results (per run: values,\n"
    "                   status, error, outputs), sensitivity\n"
    "  --quiet          no progress and no summary on stderr (failed runs are still named)\n\n"
    "outputs per run: max_area (m^2, net 0's corner polygon, largest), max_area_time (s),\n"
    "max_penetration (m, deepest contact), centroid_drift (m, the knots' centroid, first to last\n"
    "frame).\n\n"
    "exit status: 0 SWEEP.h5 written (some runs may have failed: see \"failed\"), 1 bad\n"
    "scenario, parameter path or output, or every run failed (nothing written), 2 usage error.\n";

std::string OverridesText(const std::vector<netsim::ScenarioOverride>& overrides, size_t skip) {
  std::string text;
  for (size_t i = skip; i < overrides.size(); ++i)
    text += (text.empty() ? "" : " ") + overrides[i].Text();
  return text;
}

void PrintJson(const std::string& scenario, const std::vector<netsim::SweepParameter>& parameters,
               const std::vector<netsim::SweepPoint>& grid, const netsim::SweepResult& result,
               const std::vector<std::vector<netsim::Sensitivity>>& sensitivity,
               const std::string& out, const std::string& report) {
  JsonWriter json;
  json.BeginObject();
  json.Key("scenario").String(scenario);
  json.Key("runs").Int(static_cast<long long>(result.runs.size()));
  json.Key("ok").Int(static_cast<long long>(result.runs.size()) - result.failed());
  json.Key("failed").Int(result.failed());
  json.Key("jobs").Int(result.jobs);
  json.Key("ranks").Int(result.ranks);
  json.Key("mpi").Bool(netsim::MpiSession::BuiltIn());
  json.Key("wall_s").Number(result.wall_s);
  json.Key("runs_per_hour").Number(result.RunsPerHour());
  json.Key("parameters").BeginArray();
  for (const netsim::SweepParameter& p : parameters) {
    json.BeginObject();
    json.Key("path").String(p.path);
    json.Key("from").Number(p.from);
    json.Key("to").Number(p.to);
    json.Key("count").Int(p.count);
    json.Key("values").BeginArray();
    for (double v : p.Values()) json.Number(v);
    json.EndArray();
    json.EndObject();
  }
  json.EndArray();
  json.Key("results").BeginArray();
  for (const netsim::SweepRun& run : result.runs) {
    json.BeginObject();
    json.Key("run").Int(run.index);
    json.Key("values").BeginArray();
    for (double v : grid[run.index].values) json.Number(v);
    json.EndArray();
    json.Key("status").String(netsim::StatusName(run.status));
    json.Key("error").String(run.error);
    // As in the file: no output for a failed run (null), whatever it reached before failing.
    for (const netsim::SweepOutputInfo& info : netsim::kSweepOutputs)
      json.Key(info.name).Number(run.ok() ? run.outputs.*info.field : NAN);
    json.Key("sim_time").Number(run.summary.sim_time);
    json.Key("steps").Int(run.summary.steps);
    json.Key("frames").Int(run.summary.frames);
    json.Key("wall_s").Number(run.summary.wall_s);
    json.Key("rank").Int(run.rank);
    json.EndObject();
  }
  json.EndArray();
  json.Key("sensitivity").BeginObject();
  for (size_t o = 0; o < netsim::kSweepOutputs.size(); ++o) {
    json.Key(netsim::kSweepOutputs[o].name).BeginArray();
    for (const netsim::Sensitivity& s : sensitivity[o]) json.Number(s.value);
    json.EndArray();
  }
  json.EndObject();
  json.Key("output").String(out);
  json.Key("report").String(report);
  json.EndObject();
  std::cout << json.str() << std::endl;
}

// The human summary on stderr: the runs, then the sensitivities as a small table.
void PrintSummary(const std::vector<netsim::SweepParameter>& parameters,
                  const netsim::SweepResult& result,
                  const std::vector<std::vector<netsim::Sensitivity>>& sensitivity,
                  const std::string& out, const std::string& report) {
  std::fprintf(stderr,
               "sweep: %zu runs, %d failed, in %.1f s (%.0f runs/hour; %d thread%s x %d "
               "process%s)\n",
               result.runs.size(), result.failed(), result.wall_s, result.RunsPerHour(),
               result.jobs, result.jobs == 1 ? "" : "s", result.ranks,
               result.ranks == 1 ? "" : "es");
  std::fprintf(stderr, "  sensitivities d ln(output)/d ln(parameter) at the grid's centre:\n");
  for (size_t q = 0; q < parameters.size(); ++q) {
    std::fprintf(stderr, "  %s:", parameters[q].path.c_str());
    for (size_t o = 0; o < netsim::kSweepOutputs.size(); ++o)
      std::fprintf(stderr, " %s %.3g%s", netsim::kSweepOutputs[o].name, sensitivity[o][q].value,
                   o + 1 < netsim::kSweepOutputs.size() ? "," : "\n");
  }
  std::fprintf(stderr, "  output      %s%s%s\n", out.c_str(), report.empty() ? "" : ", ",
               report.c_str());
}

}  // namespace

int RunSweep(const std::vector<std::string>& args) {
  // Made first under mpirun, so that an error on rank 0 can end the other ranks.
  std::unique_ptr<netsim::MpiSession> mpi;
  return RunGuarded("sweep", [&] {
    const CommandLine cl(args, {"json", "quiet", "help"},
                         {"out", "vary", "set", "report", "jobs", "decimate", "ensemble"});
    if (cl.Flag("help")) {
      std::fputs(kHelp, stdout);
      return 0;
    }
    if (cl.positional().size() != 1) throw UsageError("expected one SCENARIO.yaml");
    const std::string scenario_path = cl.positional()[0];
    const std::string out = cl.Required("out");
    const std::string report = cl.Option("report").value_or("");
    const int jobs = cl.IntOption("jobs", 0, 1, 1024);
    const int decimate = cl.IntOption("decimate", 1, 1, 1000000);
    const std::vector<netsim::ScenarioOverride> fixed = cl.Overrides("set");
    std::vector<netsim::SweepParameter> parameters;
    try {
      for (const std::string& vary : cl.Options("vary"))
        parameters.push_back(netsim::ParseVary(vary));
    } catch (const InputError& e) {
      throw UsageError(e.what());
    }
    if (parameters.empty()) throw UsageError("expected at least one --vary PATH=a:b:n");
    // Before any run: no output over the scenario or the other output, both writable.
    CheckOutputPaths({{"scenario", scenario_path}}, {{"--out", out}, {"--report", report}});

    if (netsim::MpiSession::Launched()) {
      if (!netsim::MpiSession::BuiltIn())
        throw std::runtime_error(
            "started by mpirun, but this netlab was built without MPI: every process would run "
            "the whole sweep (install libopenmpi-dev and rebuild, or run without mpirun and "
            "--jobs N)");
      mpi = std::make_unique<netsim::MpiSession>();
    }
    const bool root = mpi == nullptr || mpi->rank() == 0;
    // The paths before any run: an unknown one is an error naming it (on every rank alike).
    netsim::CheckSweepParameters(scenario_path, fixed, parameters);
    // --ensemble N: N runs, each parameter at one of its values (each equally often, shuffled),
    // instead of the full grid: the spread netlab score --sim-ensemble reads.
    const int ensemble = cl.Option("ensemble") ? cl.IntOption("ensemble", 0, 2, 100000) : 0;
    const std::vector<netsim::SweepPoint> grid =
        ensemble > 0 ? netsim::SweepEnsemble(fixed, parameters, ensemble)
                     : netsim::SweepGrid(fixed, parameters);
    std::vector<std::vector<netsim::ScenarioOverride>> sets;
    for (const netsim::SweepPoint& point : grid) sets.push_back(point.overrides);

    // Rank 0 writes the file and the report, put in place together when both are complete and
    // some run succeeded; on any failure neither is, and no partial file is left.
    std::optional<OutputSet> outputs;
    if (root) outputs.emplace(std::vector<std::string>{out, report});
    // An error in writing must end every rank, or they would wait for rank 0.
    std::unique_ptr<netsim::SweepFileWriter> writer;
    if (root) {
      try {
        netsim::SweepFileHeader header;
        header.scenario_path = scenario_path;
        header.scenario_text = netsim::ReadScenarioText(scenario_path);
        header.fixed = fixed;
        header.parameters = parameters;
        header.grid = grid;
        header.decimate = decimate;
        writer = std::make_unique<netsim::SweepFileWriter>(out, header);
      } catch (const std::exception& e) {
        if (mpi && mpi->size() > 1) {
          std::fprintf(stderr, "netlab sweep: error: %s\n", e.what());
          mpi->Abort(1);
        }
        throw;
      }
    }

    const bool quiet = cl.Flag("quiet");
    ProgressBar bar("sweep", root && !quiet);
    int failed = 0;
    double shown = 0.0;  // runs done as last shown: never backwards (a collected run's part)
    auto show = [&](double done, int total) {
      shown = std::max(shown, done);
      bar.Update({"runs", shown, static_cast<double>(total), std::to_string(failed) + " failed"});
    };
    netsim::SweepOptions options;
    options.jobs = jobs;
    options.decimate = decimate;
    options.keep_tracks = false;  // written as they come
    options.mpi = mpi.get();
    options.on_run = [&](const netsim::SweepRun& run, int done, int total) {
      writer->AddRun(run);
      if (!run.ok()) {
        ++failed;
        bar.Break();
        // A blow-up's message says what happened; the others are headed by the status.
        const std::string what =
            run.status == netsim::SweepRun::Status::kBlewUp
                ? run.error
                : std::string(netsim::StatusName(run.status)) + ": " + run.error;
        std::fprintf(stderr, "netlab sweep: run %d (%s): %s\n", run.index,
                     OverridesText(run.overrides, fixed.size()).c_str(), what.c_str());
      }
      show(done, total);
    };
    options.progress = ProgressReporter(
        [&](const Progress& p) { show(p.done, static_cast<int>(p.total)); }, InterruptToken());
    netsim::SweepResult result;
    try {
      result = netsim::RunSweep(scenario_path, sets, options);
    } catch (const std::exception& e) {
      // E.g. the disk filled while rank 0 wrote a run: the other ranks would wait for it forever.
      if (mpi && mpi->size() > 1) {
        std::fprintf(stderr, "netlab sweep: error: %s\n", e.what());
        mpi->Abort(1);
      }
      throw;
    }
    if (!root) return 0;
    bar.Break();

    auto sensitivity = netsim::ComputeSensitivities(parameters, result.runs);
    if (ensemble > 0)
      // The runs are draws, not a grid: no central difference to take.
      for (auto& per_output : sensitivity)
        for (netsim::Sensitivity& one : per_output) one = {NAN, -1, -1, "an ensemble, not a grid"};
    // A study of which no run succeeded has no result: --out and --report are left as they were
    // (each run's error is named above and in the JSON).
    if (failed == static_cast<int>(result.runs.size()) && failed > 0) {
      writer.reset();  // closes the partial file, which `outputs` removes
      if (cl.Flag("json")) PrintJson(scenario_path, parameters, grid, result, sensitivity, "", "");
      std::fprintf(stderr,
                   "netlab sweep: error: all %d runs failed (each named above); %s was "
                   "not written%s\n",
                   failed, out.c_str(),
                   std::filesystem::exists(out) ? ", the existing file is as it was" : "");
      return 1;
    }
    writer->Commit(result, sensitivity);
    if (!report.empty())
      netsim::WriteSweepReport(report, parameters, grid, result, sensitivity,
                               {scenario_path, out, fixed});
    outputs->Commit();
    if (!quiet) PrintSummary(parameters, result, sensitivity, out, report);
    if (cl.Flag("json"))
      PrintJson(scenario_path, parameters, grid, result, sensitivity, out, report);
    return 0;
  });
}

}  // namespace netlab::app
