// netlab score --measured tracks.h5[,tracks2.h5,...] --sim sim.h5 --out score.h5
//              [--report report.html] [--align none|time|rigid|time+rigid] [--json]
// Scores a simulation against measured knot tracks (libnetsim/validation/score.h); with several
// measured files (repeats of one case), scores each shot on its own, pools the test over them and
// gives the spread between them (libnetsim/validation/repeats.h). docs/score.md.

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <iostream>
#include <map>
#include <optional>

#include "app/cli/commands.h"
#include "app/cli/json_writer.h"
#include "app/command_line/command_line.h"
#include "common/errors.h"
#include "common/files.h"
#include "common/hdf5_util.h"
#include "common/output_paths.h"
#include "common/tracks/track_file.h"
#include "libnetsim/validation/repeats.h"
#include "libnetsim/validation/score.h"
#include "libnetsim/validation/score_file.h"
#include "libnetsim/validation/score_report.h"
#include "libnetsim/validation/sim_ensemble.h"
#include "libnetsim/validation/summary_fields.h"

namespace netlab::app {
namespace {

std::vector<std::string> SplitList(const std::string& text) {
  std::vector<std::string> parts;
  size_t start = 0;
  while (start <= text.size()) {
    const size_t comma = std::min(text.find(',', start), text.size());
    if (comma > start) parts.push_back(text.substr(start, comma - start));
    start = comma + 1;
  }
  return parts;
}

constexpr char kHelp[] =
    "usage: netlab score --measured tracks.h5[,tracks2.h5,...] --sim sim.h5 --out score.h5\n"
    "                    [--report report.html]\n"
    "                    [--sim-ensemble ens.h5|a.h5,b.h5,...]\n"
    "                    [--align none|time|rigid|time+rigid] [--json]\n\n"
    "Scores a simulation against measured knot tracks (the paper's sec. 4.1 validation): aligns\n"
    "them in time (and space), takes r = measured - simulated for every knot and frame the\n"
    "measurement has, its Mahalanobis distance d2 with the measured covariance, and tests\n"
    "whether the simulation is consistent with the measurement uncertainty (docs/score.md).\n\n"
    "options:\n"
    "  --measured FILES    knot tracks with /knots/covariance (netlab triangulate); a comma\n"
    "                      list of repeats of the case (the same net): each shot scored on\n"
    "                      its own (its own time offset and rigid alignment), the test pooled\n"
    "                      over them, and the spread between them per phase and knot class\n"
    "  --sim FILE          knot tracks of the simulation (netlab simulate), on the same net\n"
    "  --out FILE          score.h5: residuals, d2, per-knot/class/phase tables, alignment\n"
    "  --report FILE       also a self-contained HTML report with plots (open it in a browser)\n"
    "  --align MODE        none, time (default: fit the launch-time offset), rigid (one rigid\n"
    "                      motion meas_from_sim, 6 dof) or time+rigid\n"
    "  --time-offset S     t_sim = t_measured + S: fixed (--align none|rigid) or the centre of\n"
    "                      the search (default 0)\n"
    "  --max-time-offset S half width of the offset search, s (default 0.2)\n"
    "  --sim-sigma M       the simulation's own standard deviation, m (a dt/discretisation\n"
    "                      study), when the simulation file has no /knots/covariance (default 0)\n"
    "  --sim-ensemble F    the simulation's own spread: a netlab sweep file (its finished runs)\n"
    "                      or a comma list of simulation files of the same net; the per\n"
    "                      knot-frame covariance of the runs is added to Sigma_sim\n"
    "  --meas-sigma M      measurement standard deviation, m, for measured tracks without\n"
    "                      /knots/covariance\n"
    "  --significance A    test level: inconsistent when p < A (default 0.01)\n"
    "  --contact-time S    simulated time of first contact with the target: starts the\n"
    "                      \"contact\" phase (default: the simulation's first contact, which\n"
    "                      netlab simulate stores; none: no contact phase)\n"
    "  --max-sigma M       a measured point whose largest sigma exceeds M (m) is left out of the\n"
    "                      errors in mm (RMS, maximum, tables, plots), not of d2 (default: 10x\n"
    "                      the median sigma of the compared points)\n"
    "  --quiet             no summary on stderr\n"
    "  --json              print one JSON summary object on stdout as the last output: frames,\n"
    "                      knots, points, rms_mm, rms_percent_of_side, max_mm, mean_d2, dof,\n"
    "                      p_value, verdict, time_offset_s, time_offset_sigma_s, skill,\n"
    "                      per_class (corner/edge/inner rms_mm), headline, left_out_points,\n"
    "                      weighted_rms_mm, degenerate_points, wall_s and more; with repeats\n"
    "                      also shots (per file: verdict, mean_d2, rms_mm, time_offset_s),\n"
    "                      pooled (verdict, mean_d2, dof, p_value) and repeat_spread_mm per\n"
    "                      phase; the top-level verdict, mean_d2, dof, p_value are pooled\n\n"
    "exit status: 0 scored (whatever the verdict), 1 bad input, 2 usage error.\n";

// The variances a knot-track file may state, m^2: a standard deviation of 1e-20 m to 1 km (netlab's
// own triangulation of noise-free synthetic labels states ~1e-32 m^2). Outside, d^2 = e^T C^-1 e
// and the weights built from it overflow or vanish (1e300 m^2 everywhere read as "consistent").
constexpr double kMinVariance = 1e-40, kMaxVariance = 1e6;

// Refuses a covariance of a valid knot-frame with a variance outside [kMinVariance,
// kMaxVariance], naming the file, frame and knot.
void CheckCovariances(const KnotTracks& tracks, const std::string& path) {
  if (tracks.covariance.empty()) return;
  const int knots = tracks.knots();
  for (size_t i = 0; i < tracks.covariance.size(); ++i) {
    if (i < tracks.valid.size() && !tracks.valid[i]) continue;
    for (int a = 0; a < 3; ++a) {
      const double v = tracks.covariance[i](a, a);
      if (v >= kMinVariance && v <= kMaxVariance) continue;
      char text[160];
      std::snprintf(text, sizeof(text), "variance %.3g m^2 (sigma %.3g m)", v,
                    std::sqrt(std::max(v, 0.0)));
      throw InputError(path + ":/knots/covariance: frame " + std::to_string(i / knots) + ", knot " +
                       std::to_string(i % knots) + ": " + text +
                       " is outside 1e-40..1e6 m^2 (sigma 1e-20 m to 1 km): no position is "
                       "measured so; fix the file, or give --meas-sigma / --sim-sigma for a file "
                       "without covariances");
    }
  }
}

// Refuses a file that holds nothing to compare: a measurement of one frame (no span of time to
// align or compare; it read "no overlap in time"), or every knot invalid in every frame.
void CheckSomethingToCompare(const KnotTracks& tracks, const std::string& path, bool measured) {
  if (measured && tracks.frames() < 2)
    throw InputError(path + ": " + std::to_string(tracks.frames()) +
                     (tracks.frames() == 1 ? " frame" : " frames") +
                     ": a score compares a flight over time, at least 2 frames");
  for (uint8_t valid : tracks.valid)
    if (valid) return;
  throw InputError(path + ": no knot is valid in any of its " + std::to_string(tracks.frames()) +
                   " frames (/knots/valid all 0): nothing to compare");
}

// Refuses a /knots/grid that lists a knot twice (and so leaves another out): the knots would be
// compared with the wrong ones.
void CheckGrid(const KnotTracks& tracks, const std::string& path) {
  std::map<std::array<int, 3>, int> first;  // (net, row, col) -> its first index
  for (int k = 0; k < tracks.knots(); ++k) {
    const int net = tracks.net.empty() ? 0 : tracks.net[k];
    const auto [it, fresh] =
        first.emplace(std::array<int, 3>{net, tracks.grid[k][0], tracks.grid[k][1]}, k);
    if (!fresh)
      throw InputError(path + ":/knots/grid: knots " + std::to_string(it->second) + " and " +
                       std::to_string(k) + " are both (" + std::to_string(tracks.grid[k][0]) +
                       ", " + std::to_string(tracks.grid[k][1]) + ")" +
                       (tracks.net.empty() ? "" : " of net " + std::to_string(net)) +
                       ": each knot must be listed once");
  }
}

// Refuses a /contact_start that is there but holds no time (NaN, infinite): netlab leaves the
// dataset out when the simulation had no contact, so a NaN one is a broken file, not "none".
void CheckContactStartDataset(const std::string& path) {
  const h5::Id file = h5::OpenFileReadOnly(path);
  if (!h5::Exists(file.get(), "/contact_start")) return;
  double t = 0.0;
  h5::ReadDataset(file.get(), "/contact_start", H5T_NATIVE_DOUBLE, &t);
  if (!std::isfinite(t))
    throw InputError(path + ":/contact_start is " + std::to_string(t) +
                     ", not a time (a simulation without contact has no /contact_start)");
}

// Refuses a contact time (given, or the simulation's /contact_start) outside the simulation's
// time: the contact phase would start before the first frame or after the last.
void CheckContactTime(double t, const std::string& what, const KnotTracks& sim,
                      const std::string& sim_path) {
  if (!std::isfinite(t) || sim.time.empty()) return;
  if (t >= sim.time.front() && t <= sim.time.back()) return;
  char span[120];
  std::snprintf(span, sizeof(span), "%.6g s is outside the time of the simulation ", t);
  char range[80];
  std::snprintf(range, sizeof(range), ", [%.6g, %.6g] s", sim.time.front(), sim.time.back());
  throw InputError(what + " " + span + sim_path + range);
}

// The measured files of --measured: one, or a comma list of repeats. An empty item is a usage
// error; a file given twice (by the same name or another path to it) a bad input.
std::vector<std::string> MeasuredPaths(const std::string& list) {
  std::vector<std::string> paths;
  size_t start = 0;
  while (true) {
    const size_t comma = list.find(',', start);
    const std::string item = list.substr(start, comma == std::string::npos ? comma : comma - start);
    if (item.empty())
      throw UsageError("--measured '" + list + "': an empty file name in the list (item " +
                       std::to_string(paths.size() + 1) + ")");
    paths.push_back(item);
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  for (size_t i = 0; i < paths.size(); ++i)
    for (size_t j = 0; j < i; ++j) {
      std::error_code error;
      if (paths[i] == paths[j] || std::filesystem::equivalent(paths[i], paths[j], error))
        throw InputError("--measured: " + paths[i] + " (item " + std::to_string(i + 1) + ") is " +
                         (paths[i] == paths[j] ? "" : paths[j] + ", ") + "item " +
                         std::to_string(j + 1) +
                         " again: repeats are different shots, each given once");
    }
  return paths;
}

void JsonPhaseRows(JsonWriter& json, const std::vector<netsim::SpreadRow>& rows) {
  json.BeginObject();
  for (const netsim::SpreadRow& row : rows) json.Key(row.name).Number(row.rms_m * 1e3);
  json.EndObject();
}

// With repeats: one object per shot, the pooled test and the spread between the shots.
void JsonRepeats(JsonWriter& json, const netsim::RepeatsResult& repeats) {
  const netsim::RepeatsSummary& r = repeats.summary;
  json.Key("shots").BeginArray();
  for (size_t i = 0; i < repeats.shots.size(); ++i) {
    const netsim::ScoreSummary& s = repeats.shots[i].summary;
    json.BeginObject();
    json.Key("path").String(r.names[i]);
    json.Key("verdict").String(netsim::VerdictName(s.verdict));
    json.Key("mean_d2").Number(s.mean_d2);
    json.Key("dof").Number(s.dof);
    json.Key("p_value").Number(s.p_value);
    json.Key("points").Int(s.points);
    json.Key("rms_mm").Number(s.rms_m * 1e3);
    json.Key("max_mm").Number(s.max_m * 1e3);
    json.Key("time_offset_s").Number(s.time_offset_s);
    json.Key("time_offset_sigma_s").Number(s.time_offset_sigma_s);
    json.Key("spread_time_offset_s").Number(r.spread_time_offset_s[i]);
    json.EndObject();
  }
  json.EndArray();
  json.Key("pooled").BeginObject();
  json.Key("verdict").String(netsim::VerdictName(r.verdict));
  json.Key("mean_d2").Number(r.mean_d2);
  json.Key("dof").Number(r.dof);
  json.Key("p_value").Number(r.p_value);
  json.Key("points").Int(r.points);
  json.Key("effective_points").Number(r.effective_points);
  json.Key("critical_mean_d2").Number(r.critical_mean_d2);
  json.Key("margin").Number(r.margin);
  json.Key("rms_mm").Number(r.rms_m * 1e3);
  json.EndObject();
  json.Key("repeat_spread_mm");
  JsonPhaseRows(json, r.spread_per_phase);
  json.Key("repeat_spread_per_class_mm");
  JsonPhaseRows(json, {r.spread_per_class.begin(), r.spread_per_class.end()});
  json.Key("repeat_spread_all_mm").Number(r.spread.rms_m * 1e3);
}

// The text summary's lines on the repeats: one per shot, the pooled test, the spread.
std::string RepeatsReport(const netsim::RepeatsResult& repeats) {
  const netsim::RepeatsSummary& r = repeats.summary;
  std::string text = "repeats: " + std::to_string(repeats.shots.size()) + " shots\n";
  char line[400];
  for (size_t i = 0; i < repeats.shots.size(); ++i) {
    const netsim::ScoreSummary& s = repeats.shots[i].summary;
    std::snprintf(line, sizeof(line),
                  "  %s: offset %.3f ms (clock %+.3f ms from the first shot's), RMS %.4g mm, mean "
                  "d2 %.4g, p %.3g, %s\n",
                  r.names[i].c_str(), s.time_offset_s * 1e3, r.spread_time_offset_s[i] * 1e3,
                  s.rms_m * 1e3, s.mean_d2, s.p_value, netsim::VerdictName(s.verdict).c_str());
    text += line;
  }
  std::snprintf(line, sizeof(line),
                "  pooled: %d knot-frames, RMS %.4g mm, mean d2 %.4g (dof %.0f, rejects above "
                "%.4g), p %.3g, %s\n  spread between the shots: %.4g mm",
                r.points, r.rms_m * 1e3, r.mean_d2, r.dof, r.critical_mean_d2, r.p_value,
                netsim::VerdictName(r.verdict).c_str(), r.spread.rms_m * 1e3);
  text += line;
  // The phases the shots share frames of (the others have no spread to give).
  for (const netsim::SpreadRow& row : r.spread_per_phase) {
    if (row.points == 0) continue;
    std::snprintf(line, sizeof(line), "; %s %.4g", row.name.c_str(), row.rms_m * 1e3);
    text += line;
  }
  return text + " mm\n";
}

// The JSON summary: every field summary_fields.h prints in the JSON, in its order; with repeats
// then shots, pooled and the spread.
void PrintJson(const netsim::ScoreSummary& s, const netsim::RepeatsResult* repeats = nullptr) {
  using netsim::SummaryKind;
  JsonWriter json;
  json.BeginObject();
  for (const netsim::SummaryField& field : netsim::SummaryFields()) {
    if (!(field.outputs & netsim::kInJson)) continue;
    const netsim::SummaryValue value = field.value(s);
    json.Key(std::string(field.key));
    switch (field.kind) {
      case SummaryKind::kInt: json.Int(static_cast<long long>(value.number)); break;
      case SummaryKind::kNumber: json.Number(value.number); break;
      case SummaryKind::kText: json.String(value.text); break;
      case SummaryKind::kFlag: json.Bool(value.number != 0.0); break;
      case SummaryKind::kVector3: json.Vector3(value.vector); break;
      case SummaryKind::kRows:
        json.BeginObject();
        for (const netsim::ScoreRow& row : value.rows) json.Key(row.name).Number(row.rms_m * 1e3);
        json.EndObject();
        break;
      case SummaryKind::kPhases:
        // Per phase, the error beside the two contributions to its expectation.
        json.BeginArray();
        for (const netsim::ScoreRow& row : value.rows) {
          json.BeginObject();
          json.Key("name").String(row.name);
          json.Key("start_s").Number(row.start_s);
          json.Key("end_s").Number(row.end_s);
          json.Key("points").Int(row.points);
          json.Key("rms_mm").Number(row.rms_m * 1e3);
          json.Key("sigma_sim_mm").Number(row.sigma_sim_m * 1e3);
          json.Key("sigma_meas_mm").Number(row.sigma_meas_m * 1e3);
          json.Key("mean_d2").Number(row.mean_d2);
          json.EndObject();
        }
        json.EndArray();
        break;
      case SummaryKind::kLines:
        json.BeginArray();
        for (const std::string& line : value.lines) json.String(line);
        json.EndArray();
        break;
    }
  }
  if (repeats) JsonRepeats(json, *repeats);
  json.EndObject();
  std::cout << json.str() << std::endl;
}

}  // namespace

int RunScore(const std::vector<std::string>& args) {
  return RunGuarded("score", [&] {
    const CommandLine cl(
        args, {"json", "quiet", "help"},
        {"measured", "sim", "out", "report", "align", "time-offset", "max-time-offset", "sim-sigma",
         "meas-sigma", "significance", "contact-time", "max-sigma", "sim-ensemble"});
    if (cl.Flag("help")) {
      std::fputs(kHelp, stdout);
      return 0;
    }
    if (!cl.positional().empty())
      throw UsageError("unexpected argument '" + cl.positional()[0] + "'");
    const auto start = std::chrono::steady_clock::now();
    const std::vector<std::string> measured_paths = MeasuredPaths(cl.Required("measured"));
    const std::string& measured_path = measured_paths[0];
    const std::string sim_path = cl.Required("sim");
    const std::string out = cl.Required("out");
    const std::string report = cl.Option("report").value_or("");
    const std::string ensemble = cl.Option("sim-ensemble").value_or("");
    netsim::ScoreOptions options;
    const std::string align = cl.Option("align").value_or("time");
    if (!netsim::ParseAlignment(align, &options.alignment))
      throw UsageError("--align expects none, time, rigid or time+rigid, got '" + align + "'");
    options.time_offset_s = cl.DoubleOption("time-offset", 0.0, -1e6, 1e6);
    options.max_time_offset_s = cl.DoubleOption("max-time-offset", 0.2, 0.0, 1e6);
    options.sim_sigma_m = cl.DoubleOption("sim-sigma", 0.0, 0.0, 1e3);
    options.meas_sigma_m = cl.DoubleOption("meas-sigma", 0.0, 0.0, 1e3);
    options.significance = cl.DoubleOption("significance", 0.01, 1e-12, 0.5);
    options.max_sigma_m = cl.DoubleOption("max-sigma", 0.0, 1e-12, 1e6);
    if (cl.Option("contact-time"))
      options.contact_time_s = cl.DoubleOption("contact-time", 0.0, -1e6, 1e6);
    std::string why;
    if (!options.IsValid(&why)) throw UsageError(why);
    const bool quiet = cl.Flag("quiet");
    // Before any work: no output over an input or the other output, every output writable.
    std::vector<NamedPath> inputs;
    for (const std::string& path : measured_paths) inputs.push_back({"--measured", path});
    inputs.push_back({"--sim", sim_path});
    if (!ensemble.empty())
      for (const std::string& part : SplitList(ensemble))
        inputs.push_back({"--sim-ensemble", part});
    CheckOutputPaths(inputs, {{"--out", out}, {"--report", report}});

    const std::string measured_list = cl.Required("measured");
    if (!quiet)
      std::fprintf(stderr, "reading %s and %s\n", measured_list.c_str(), sim_path.c_str());
    std::vector<KnotTracks> shots;
    for (const std::string& path : measured_paths) {
      shots.push_back(ReadKnotTracks(path));
      CheckSomethingToCompare(shots.back(), path, true);
      CheckGrid(shots.back(), path);
      CheckCovariances(shots.back(), path);
    }
    const KnotTracks& measured = shots[0];
    std::vector<const KnotTracks*> shot_tracks;
    for (const KnotTracks& shot : shots) shot_tracks.push_back(&shot);
    netsim::CheckSameNet(shot_tracks, measured_paths);
    KnotTracks sim = ReadKnotTracks(sim_path);
    CheckSomethingToCompare(sim, sim_path, false);
    CheckGrid(sim, sim_path);
    CheckCovariances(sim, sim_path);
    const bool sim_had_covariance = !sim.covariance.empty();
    CheckContactTime(options.contact_time_s, "--contact-time", sim, sim_path);
    CheckContactStartDataset(sim_path);
    if (!std::isfinite(options.contact_time_s))
      CheckContactTime(sim.contact_start_s, sim_path + ":/contact_start", sim, sim_path);
    if (!quiet)
      std::fprintf(stderr, "scoring %d x %d knot-frames%s against %d simulated frames\n",
                   measured.frames(), measured.knots(),
                   shots.size() > 1
                       ? (", and " + std::to_string(shots.size() - 1) + " repeats").c_str()
                       : "",
                   sim.frames());
    int members = 0;
    double ensemble_max_sigma_m = 0.0;
    if (!ensemble.empty()) {
      if (!quiet) std::fprintf(stderr, "reading the ensemble %s\n", ensemble.c_str());
      const std::vector<netsim::EnsembleMember> runs = netsim::ReadEnsemble(ensemble);
      members = static_cast<int>(runs.size());
      sim = netsim::AddEnsembleCovariance(sim, sim_path, runs, &ensemble_max_sigma_m);
    }
    // One shot: scored as it is. Repeats: each on its own, then pooled (the result shown is the
    // first shot's with the pooled test).
    std::optional<netsim::RepeatsResult> repeats;
    if (shots.size() > 1)
      repeats = netsim::ScoreRepeats(shot_tracks, measured_paths, sim, options, sim_path);
    netsim::ScoreResult result =
        repeats ? repeats->combined
                : netsim::Score(measured, sim, options, measured_path, sim_path);
    if (members > 0) {
      char text[200];
      std::snprintf(text, sizeof(text),
                    "the spread of %d ensemble runs (%s; largest sigma %.3g mm)%s", members,
                    ensemble.c_str(), ensemble_max_sigma_m * 1e3,
                    sim_had_covariance ? " added to the simulation's /knots/covariance" : "");
      result.summary.ensemble_members = members;
      result.summary.sim_uncertainty = text;
      if (repeats)
        for (netsim::ScoreResult& shot : repeats->shots) {
          shot.summary.ensemble_members = members;
          shot.summary.sim_uncertainty = text;
        }
    }
    const netsim::RepeatsResult* pooled = repeats ? &*repeats : nullptr;
    {
      // Both put in place together once both are complete.
      OutputSet outputs({out, report});
      netsim::WriteScore(out, result, pooled);
      if (!report.empty()) {
        netsim::ReportInfo info;
        info.measured_path = measured_list;
        info.sim_path = sim_path;
        info.score_path = out;
        netsim::WriteScoreReport(report, result, info, pooled);
      }
      outputs.Commit();
    }
    result.summary.output_path = out;
    result.summary.report_path = report;
    result.summary.wall_s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (!quiet || !cl.Flag("json")) {
      std::cerr << result.summary.BriefReport();
      if (pooled) std::cerr << RepeatsReport(*pooled);
      std::cerr << "  wrote " << out << (report.empty() ? "" : " and " + report) << "\n";
    }
    if (cl.Flag("json")) PrintJson(result.summary, pooled);
    return 0;
  });
}

}  // namespace netlab::app
