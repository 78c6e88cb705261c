// netlab fit SCENARIO.yaml [SCENARIO2.yaml ...] --measured tracks.h5[,tracks2.h5,...]
//            --free PARAMS --out fit.yaml [--prior material.yaml] [--set PATH=VALUE ...] [--json]

#include <glog/logging.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "app/cli/commands.h"
#include "app/cli/json_writer.h"
#include "app/cli/progress_bar.h"
#include "app/command_line/command_line.h"
#include "common/errors.h"
#include "common/files.h"
#include "common/output_paths.h"
#include "libnetsim/characterization/material_file.h"
#include "libnetsim/identification/fit_file.h"
#include "libnetsim/identification/shot_fit.h"

namespace netlab::app {
namespace {

constexpr char kHelp[] =
    "usage: netlab fit SCENARIO.yaml [SCENARIO2.yaml ...] --measured TRACKS.h5[,TRACKS2.h5,...]\n"
    "                  --free PARAMS --out FIT.yaml\n"
    "                  [--prior MATERIAL.yaml[,...]] [--set PATH=VALUE ...] [--time-offset S]\n"
    "                  [--max-time-offset S] [--meas-sigma M] [--sim-sigma M] [--starts N]\n"
    "                  [--scan N] [--max-iterations N] [--step H] [--jobs N] [--json]\n"
    "                  [--quiet]\n\n"
    "Identifies parameters of a shot from its measured knot tracks (docs/fit.md): finds the\n"
    "values of the free parameters that make SCENARIO.yaml's simulation agree best with\n"
    "TRACKS.h5, weighing every knot-frame by its covariance as `netlab score` does\n"
    "(Levenberg-Marquardt; each iteration runs one simulation per scenario parameter, in\n"
    "parallel). Reports each estimate with its standard uncertainty and whether the flight data\n"
    "determined it or only the prior did. Progress and an ETA go to stderr.\n\n"
    "Several shots (one scenario and one track file each, in the same order) are fitted at once:\n"
    "material and drag values are shared by every shot, the other parameters are each shot's\n"
    "own, named 1:nets.0.velocity.0, 2:time_offset, ...\n\n"
    "options:\n"
    "  --measured FILES measured knot tracks (netlab triangulate), on the scenario's net; one\n"
    "                   per scenario, comma-separated\n"
    "  --free PARAMS    comma-separated: dotted paths of the scenario as `simulate --set`\n"
    "                   names them (materials.nylon_1mm.bend_stiffness, drag.drag_coefficient,\n"
    "                   nets.0.velocity: one parameter per item of a list), plus time_offset\n"
    "                   (the launch time) and frame (a rigid correction, 6 parameters)\n"
    "  --out FILE       fit.yaml: the estimates, uncertainties, correlations, the score of the\n"
    "                   fit, and the --set lines that rerun it (written via FILE.partial)\n"
    "  --prior FILES    material files of `netlab characterize` (comma-separated): each value\n"
    "                   given for a free parameter enters as a residual (value - prior) / sigma\n"
    "  --set PATH=VALUE change a value before fitting (repeatable): the start of a free one\n"
    "  --time-offset S  t_sim = t_measured + S: the start of time_offset, or its fixed value\n"
    "                   (default 0)\n"
    "  --max-time-offset S\n"
    "                   how far time_offset may move from its start, s (default 0.05, and at\n"
    "                   most a tenth of the shortest measured span)\n"
    "  --meas-sigma M   measurement standard deviation, m, for tracks without\n"
    "                   /knots/covariance\n"
    "  --sim-sigma M    the simulation's own standard deviation, m (default 0)\n"
    "  --starts N       Levenberg-Marquardt from N starts (the first, then N-1 drawn within a\n"
    "                   factor 2 of it), the best kept: for a cost with several minima\n"
    "                   (default 1)\n"
    "  --scan N         before the material parameters are fitted, scan each over a factor 2\n"
    "                   either way of its start, or over its prior's value +-3 sigma when that\n"
    "                   is narrower, N values either way (default 8; 0: no scan): a\n"
    "                   stiffness's cost has narrow valleys that a start far off misses\n"
    "  --max-iterations N\n"
    "                   per start (default 25)\n"
    "  --jobs N         simulations at a time (default: the machine's cores)\n"
    "  --step H         finite-difference step: of ln(value) for materials and drag, of the\n"
    "                   reference spread (docs/fit.md) times H for the others (default 1e-3)\n"
    "  --json           print one JSON summary object on stdout as the last output: parameters\n"
    "                   (name -> value, sigma, identified, ...), cost_initial, cost_final,\n"
    "                   simulations, wall_s, score, correlation\n"
    "  --quiet          no progress and no summary on stderr\n\n"
    "exit status: 0 fitted (see each parameter's \"identified\"), 1 bad input or a failed\n"
    "simulation, 2 usage error.\n";

// A number as fit.yaml writes it.
std::string Number(double value) { return netsim::FitNumber(value); }

// The table a person reads: each parameter from its start to its estimate, and what set it.
std::string Summary(const netsim::FitResult& r) {
  std::ostringstream o;
  o << "fit: " << r.parameters.size() << (r.parameters.size() == 1 ? " parameter" : " parameters")
    << " from " << r.residuals / 3 << " knot-frames; " << r.simulations << " simulations, "
    << r.iterations << " iterations, " << Number(r.wall_s) << " s\n";
  char line[256];
  std::snprintf(line, sizeof line, "  %-40s %12s %12s %12s  %s\n", "parameter", "start", "fitted",
                "sigma", "determined by");
  o << line;
  // A check's ratio, or why there is none (the run there failed or fell short).
  const auto ratio = [](double v) {
    return std::isfinite(v) ? Number(v) + "x" : std::string("failed");
  };
  // How much higher another end's cost ended: "+66.2".
  const auto rise = [](double v) {
    char text[32];
    std::snprintf(text, sizeof text, "%+.3g", v);
    return std::string(text);
  };
  for (const auto& p : r.parameters) {
    std::string by = netsim::DeterminedByName(p.determined_by);
    if (p.rough)
      by += ": the cost is rough in it (" + ratio(p.check[0]) + " / " + ratio(p.check[1]) +
            " the quadratic rise at -/+ 2 sigma), sigma means nothing";
    else if (p.ambiguous)
      by += std::isnan(p.alternative)
                ? ": the cost has another valley along it (the fit from there failed)"
                : ": the cost has another valley along it (" + Number(p.alternative) + ", cost " +
                      rise(p.alternative_rise) + ", " + p.alternative_from + ")";
    else if (!p.identified)
      by += p.has_prior ? " (the flight data adds little)" : ": not identified";
    std::snprintf(line, sizeof line, "  %-40s %12s %12s %12s  ", p.parameter.name.c_str(),
                  Number(p.parameter.start).c_str(), Number(p.value).c_str(),
                  Number(p.sigma).c_str());
    o << line << by << "\n";
  }
  o << "  stopped: " << r.termination << "\n";
  o << "  cost " << Number(r.cost_initial) << " -> " << Number(r.cost_final)
    << " (sum of squared whitened residuals";
  if (r.inflation > 1.0) o << "; uncertainties inflated x" << Number(std::sqrt(r.inflation));
  o << ")\n";
  for (size_t k = 0; k < r.scores.size(); ++k) {
    const netsim::ScoreSummary& sc = r.scores[k];
    o << "  score of the fit" << (r.scores.size() > 1 ? ", shot " + std::to_string(k + 1) : "")
      << ": RMS " << Number(sc.rms_m * 1e3) << " mm, mean d2 " << Number(sc.mean_d2) << ", "
      << netsim::VerdictName(sc.verdict) << " (p = " << Number(sc.p_value) << ")\n";
  }
  for (int i = 0; i < r.correlation.rows(); ++i)
    for (int j = i + 1; j < r.correlation.cols(); ++j)
      if (std::abs(r.correlation(i, j)) > 0.9)
        o << "  strongly correlated: " << r.parameters[i].parameter.name << " and "
          << r.parameters[j].parameter.name << " (" << Number(r.correlation(i, j))
          << "): the data fix a combination of them better than either\n";
  for (const auto& note : r.notes) o << "  note: " << note << "\n";
  return o.str();
}

void PrintJson(const netsim::FitResult& r, const std::string& out) {
  JsonWriter json;
  json.BeginObject();
  json.Key("parameters").BeginObject();
  for (const auto& p : r.parameters) {
    json.Key(p.parameter.name).BeginObject();
    json.Key("value").Number(p.value);
    json.Key("sigma").Number(p.sigma);
    json.Key("identified").Bool(p.identified);
    json.Key("rough").Bool(p.rough);
    json.Key("ambiguous").Bool(p.ambiguous);
    json.Key("alternative").Number(p.alternative);
    json.Key("alternative_rise").Number(p.alternative_rise);
    json.Key("check").BeginArray().Number(p.check[0]).Number(p.check[1]).EndArray();
    json.Key("determined_by").String(netsim::DeterminedByName(p.determined_by));
    json.Key("start").Number(p.parameter.start);
    json.Key("data_sigma").Number(p.data_sigma);
    json.Key("units").String(p.parameter.units);
    if (p.has_prior) {
      json.Key("prior_value").Number(p.prior_value);
      json.Key("prior_sigma").Number(p.prior_sigma);
    }
    json.EndObject();
  }
  json.EndObject();
  json.Key("correlation").BeginArray();
  for (int i = 0; i < r.correlation.rows(); ++i) {
    json.BeginArray();
    for (int j = 0; j < r.correlation.cols(); ++j) json.Number(r.correlation(i, j));
    json.EndArray();
  }
  json.EndArray();
  json.Key("cost_initial").Number(r.cost_initial);
  json.Key("cost_final").Number(r.cost_final);
  json.Key("residuals").Int(r.residuals);
  json.Key("inflation").Number(r.inflation);
  json.Key("simulations").Int(r.simulations);
  json.Key("iterations").Int(r.iterations);
  json.Key("wall_s").Number(r.wall_s);
  json.Key("dt_s").Number(r.dt_s);
  json.Key("score").BeginObject();
  json.Key("rms_mm").Number(r.score.rms_m * 1e3);
  json.Key("mean_d2").Number(r.score.mean_d2);
  json.Key("p_value").Number(r.score.p_value);
  json.Key("verdict").String(netsim::VerdictName(r.score.verdict));
  json.EndObject();
  json.Key("set").BeginArray();
  for (const auto& s : r.fitted_set) json.String(s.Text());
  json.EndArray();
  json.Key("notes").BeginArray();
  for (const auto& note : r.notes) json.String(note);
  json.EndArray();
  json.Key("shots").BeginArray();
  for (size_t k = 0; k < r.scores.size(); ++k) {
    json.BeginObject();
    json.Key("rms_mm").Number(r.scores[k].rms_m * 1e3);
    json.Key("mean_d2").Number(r.scores[k].mean_d2);
    json.Key("verdict").String(netsim::VerdictName(r.scores[k].verdict));
    json.Key("inflation").Number(r.inflations[k]);
    json.Key("set").BeginArray();
    for (const auto& s : r.fitted_sets[k]) json.String(s.Text());
    json.EndArray();
    json.EndObject();
  }
  json.EndArray();
  json.Key("output").String(out);
  json.EndObject();
  std::cout << json.str() << std::endl;
}

// A comma-separated list of file names; an empty item is a usage error naming the option.
std::vector<std::string> SplitList(const std::string& list, const std::string& option) {
  // getline yields no item after a trailing comma: that empty name is refused as the others are.
  if (!list.empty() && list.back() == ',')
    throw UsageError("--" + option + " '" + list +
                     "': an empty file name in the list (a "
                     "trailing comma)");
  std::vector<std::string> items;
  std::istringstream in(list);
  std::string item;
  while (std::getline(in, item, ','))
    if (item.empty()) {
      throw UsageError("--" + option + " '" + list + "': an empty file name in the list");
    } else {
      items.push_back(item);
    }
  return items;
}

// The priors of every material file given (comma-separated), as free-parameter names
// (materials.<name>.<key>). A file that names no free parameter is worth saying.
std::vector<netsim::FitPrior> ReadPriors(const std::string& list,
                                         const std::vector<netsim::FitParameter>& parameters,
                                         bool quiet) {
  std::vector<netsim::FitPrior> priors;
  for (const std::string& file : SplitList(list, "prior")) {
    int used = 0;
    for (const netsim::ParameterEstimate& e : netsim::ReadMaterialFile(file)) {
      netsim::FitPrior prior{"materials." + e.material + "." + e.key, e.value, e.sigma,
                             file + " (" + e.test + " test)"};
      // A sigma of 1e300 is no prior at all: said, not taken silently.
      if (e.sigma > 100.0 * std::abs(e.value))
        throw InputError(file + ": uncertainty." + e.material + "." + e.key + ".sigma: " +
                         Number(e.sigma) + " is over 100 times the value " + Number(e.value) +
                         ": a prior that constrains nothing; fix it or leave the file out of "
                         "--prior");
      for (const netsim::FitParameter& p : parameters) used += p.name == prior.name;
      priors.push_back(prior);
    }
    if (used == 0 && !quiet)
      std::fprintf(stderr, "note: %s gives no value for a free parameter; it is not used\n",
                   file.c_str());
  }
  return priors;
}

// The fit's options from the command line (all but the shots, the free parameters and priors).
netsim::FitOptions OptionsFrom(const CommandLine& cl) {
  netsim::FitOptions options;
  options.set = cl.Overrides("set");
  options.score.time_offset_s = cl.DoubleOption("time-offset", 0.0, -1e6, 1e6);
  options.score.max_time_offset_s = cl.DoubleOption("max-time-offset", 0.05, 1e-6, 1e3);
  options.score.meas_sigma_m = cl.DoubleOption("meas-sigma", 0.0, 0.0, 1e3);
  options.score.sim_sigma_m = cl.DoubleOption("sim-sigma", 0.0, 0.0, 1e3);
  options.starts = cl.IntOption("starts", 1, 1, 1000);
  options.scan_steps = cl.IntOption("scan", options.scan_steps, 0, 64);
  options.max_iterations = cl.IntOption("max-iterations", 25, 1, 10000);
  options.jobs = cl.IntOption("jobs", 0, 0, 4096);
  options.step = cl.DoubleOption("step", options.step, 1e-9, 0.1);
  return options;
}

std::string Duration(double s) {
  char text[32];
  if (s < 90) {
    std::snprintf(text, sizeof text, "%.0f s", s);
  } else {
    std::snprintf(text, sizeof text, "%.0f min", s / 60);
  }
  return text;
}

}  // namespace

int RunFit(const std::vector<std::string>& args) {
  return RunGuarded("fit", [&] {
    const CommandLine cl(
        args, {"json", "quiet", "help"},
        {"measured", "free", "out", "prior", "set", "time-offset", "max-time-offset", "meas-sigma",
         "sim-sigma", "starts", "scan", "max-iterations", "jobs", "step"});
    if (cl.Flag("help")) {
      std::fputs(kHelp, stdout);
      return 0;
    }
    if (cl.positional().empty()) throw UsageError("expected SCENARIO.yaml (one per shot)");
    const std::vector<std::string> scenarios = cl.positional();
    const std::vector<std::string> measured_paths = SplitList(cl.Required("measured"), "measured");
    if (measured_paths.size() != scenarios.size())
      throw UsageError("--measured names " + std::to_string(measured_paths.size()) +
                       " track files for " + std::to_string(scenarios.size()) +
                       " scenarios: one per shot, in the same order");
    const std::string free = cl.Required("free");
    const std::string out = cl.Required("out");
    netsim::FitOptions options = OptionsFrom(cl);
    const bool quiet = cl.Flag("quiet");
    // Before any work: fit.yaml over a scenario, a measured file or the prior is refused.
    std::vector<NamedPath> inputs;
    for (const std::string& path : scenarios) inputs.push_back({"scenario", path});
    for (const std::string& path : measured_paths) inputs.push_back({"--measured", path});
    inputs.push_back({"--prior", cl.Option("prior").value_or("")});
    CheckOutputPaths(inputs, {{"--out", out}});
    // Ceres' own warnings (a rejected step is part of the method) would bury netlab's lines.
    FLAGS_minloglevel = google::GLOG_ERROR;
    // A line per iteration: where the fit is, its cost, the simulations, the time so far and an
    // upper bound of the time left (the simulations left at the pace so far).
    ProgressBar bar("fit", !quiet);
    const auto fit_start = std::chrono::steady_clock::now();
    options.progress = bar.Reporter().Mapped([fit_start](Progress p) {
      const double elapsed =
          std::chrono::duration<double>(std::chrono::steady_clock::now() - fit_start).count();
      const double eta = p.done > 0 ? elapsed / p.done * (p.total - p.done) : 0.0;
      p.detail += ", " + std::to_string(static_cast<long>(p.done)) + " simulations, " +
                  Duration(elapsed) + ", ETA <= " + Duration(eta);
      p.done = p.total = 0;  // the detail says it all
      return p;
    });

    const std::vector<netsim::FitParameter> parameters =
        netsim::ParseFreeParameters(free, scenarios, options.set, options.score.time_offset_s);
    if (const auto prior = cl.Option("prior"))
      options.priors = ReadPriors(*prior, parameters, quiet);
    std::vector<KnotTracks> measured;
    std::vector<netsim::FitShotInput> shots;
    for (const std::string& path : measured_paths) measured.push_back(ReadKnotTracks(path));
    for (size_t k = 0; k < scenarios.size(); ++k) {
      shots.push_back({scenarios[k], &measured[k], measured_paths[k]});
      if (!quiet)
        std::fprintf(stderr, "shot %zu: %s against %s (%d frames x %d knots)\n", k + 1,
                     scenarios[k].c_str(), measured_paths[k].c_str(), measured[k].frames(),
                     measured[k].knots());
    }
    if (!quiet) {
      for (const std::string& path : scenarios)
        for (const std::string& note :
             netsim::ResolutionNotes(netsim::LoadScenario(path, options.set), parameters, path))
          std::fprintf(stderr, "note: %s\n", note.c_str());
      std::fprintf(stderr, "fitting %zu parameter%s\n", parameters.size(),
                   parameters.size() == 1 ? "" : "s");
    }
    const netsim::FitResult result = netsim::FitShots(shots, parameters, options);
    bar.Break();
    netsim::WriteFit(out, scenarios, measured_paths, result);
    if (!quiet || !cl.Flag("json")) std::cerr << Summary(result) << "  wrote " << out << "\n";
    if (cl.Flag("json")) PrintJson(result, out);
    return 0;
  });
}

}  // namespace netlab::app
