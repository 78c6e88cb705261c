#include "libnetsim/sweep/sweep_report.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "common/files.h"
#include "common/html.h"

namespace netlab::netsim {
namespace {

using html::Escape;
using html::Fixed;
using html::Num;
using html::Row;
using html::Ticks;

// Okabe-Ito: colours that stay apart for colour-blind readers.
constexpr const char* kColours[6] = {"#0072b2", "#d55e00", "#009e73",
                                     "#cc79a7", "#e69f00", "#56b4e9"};
constexpr int kMaxSeries = 6;

// How each output is shown: a scale from SI and its unit.
struct Display {
  double scale;
  const char* unit;
};
constexpr Display kDisplay[4] = {{1.0, "m²"}, {1.0, "s"}, {1e3, "mm"}, {1.0, "m"}};

// The last key of a dotted path: what a legend or a column has room for.
std::string ShortName(const std::string& path) {
  const size_t dot = path.rfind('.');
  return dot == std::string::npos ? path : path.substr(dot + 1);
}

// A value with 4 significant digits, for labels.
std::string Short(double v) { return Num(v, 4); }

// A tick's label: as many significant digits as the step needs to tell neighbours apart
// (1.00008 and 1.00012, not 1 and 1).
std::string TickText(double t, double step) {
  const double top = std::max(std::abs(t), step);
  const int digits = std::clamp(
      static_cast<int>(std::floor(std::log10(top)) - std::floor(std::log10(step))) + 1, 1, 12);
  return Num(t, digits);
}

double TickStep(const std::vector<double>& ticks) {
  return ticks.size() > 1 ? ticks[1] - ticks[0] : 1.0;
}

// The lines of one parameter's plots: each combination of the other parameters' value indices
// (all of them up to kMaxSeries, else the one at their middle values), the runs along the
// parameter for each.
struct Line {
  std::string name;       // "other=value, ..." or "" when there is no other parameter
  std::vector<int> runs;  // run index per value of the parameter
};

std::vector<Line> LinesAlong(const std::vector<SweepParameter>& parameters, size_t q) {
  int combos = 1;
  for (size_t o = 0; o < parameters.size(); ++o)
    if (o != q) combos *= parameters[o].count;
  std::vector<std::vector<int>> others;  // value index per parameter (q's ignored)
  if (combos <= kMaxSeries) {
    for (int c = 0; c < combos; ++c) {
      std::vector<int> at(parameters.size(), 0);
      int rest = c;
      for (size_t o = parameters.size(); o-- > 0;) {
        if (o == q) continue;
        at[o] = rest % parameters[o].count;
        rest /= parameters[o].count;
      }
      others.push_back(at);
    }
  } else {
    std::vector<int> at(parameters.size());
    for (size_t o = 0; o < parameters.size(); ++o) at[o] = (parameters[o].count - 1) / 2;
    others.push_back(at);
  }
  std::vector<Line> lines;
  for (std::vector<int> at : others) {
    Line line;
    for (size_t o = 0; o < parameters.size(); ++o) {
      if (o == q || parameters[o].count < 2) continue;
      line.name += (line.name.empty() ? "" : ", ") + parameters[o].path + " = " +
                   Short(parameters[o].Values()[at[o]]);
    }
    for (int i = 0; i < parameters[q].count; ++i) {
      at[q] = i;
      line.runs.push_back(GridIndex(parameters, at));
    }
    lines.push_back(line);
  }
  return lines;
}

constexpr html::PlotFrame kFrame{400, 260, 64, 14, 14, 44, 14};

// One output against one parameter: a line per Line, a dot per finished run, a red cross on the
// bottom axis where a run failed.
std::string Plot(const std::string& id, const std::vector<double>& x_values,
                 const std::vector<Line>& lines, const std::vector<SweepRun>& runs, size_t output,
                 const std::string& x_label) {
  const auto field = kSweepOutputs[output].field;
  const double scale = kDisplay[output].scale;
  double x0 = *std::min_element(x_values.begin(), x_values.end());
  double x1 = *std::max_element(x_values.begin(), x_values.end());
  double y0 = INFINITY, y1 = -INFINITY;
  for (const Line& line : lines)
    for (int r : line.runs)
      if (runs[r].ok() && std::isfinite(runs[r].outputs.*field)) {
        y0 = std::min(y0, runs[r].outputs.*field * scale);
        y1 = std::max(y1, runs[r].outputs.*field * scale);
      }
  if (!std::isfinite(y0)) y0 = 0, y1 = 1;
  if (y1 - y0 <= 1e-12 * std::max(std::abs(y0), std::abs(y1))) {
    // Flat: a band around the value, so the line sits mid-plot instead of on an edge.
    const double pad = y0 == 0 ? 1.0 : 0.05 * std::abs(y0);
    y0 -= pad, y1 += pad;
  } else {
    const double pad = 0.08 * (y1 - y0);
    y0 -= pad, y1 += pad;
  }
  if (x1 <= x0) x0 -= 0.5 * std::max(1.0, std::abs(x0)), x1 = x0 + std::max(1.0, std::abs(x0));
  const double xpad = 0.04 * (x1 - x0);
  x0 -= xpad, x1 += xpad;
  auto px = [&](double x) { return kFrame.X(x, x0, x1); };
  auto py = [&](double y) { return kFrame.Y(y, y0, y1); };
  std::ostringstream o;
  o << "<svg id=\"" << id << "\" class=\"plot\" viewBox=\"0 0 " << kFrame.width << " "
    << kFrame.height << "\" width=\"" << kFrame.width << "\" height=\"" << kFrame.height << "\">\n";
  const std::vector<double> y_ticks = Ticks(y0, y1, 4), x_ticks = Ticks(x0, x1, 4);
  html::PlotAxes(
      o, kFrame, x0, x1, y0, y1, x_ticks, y_ticks,
      [&](double t) { return TickText(t, TickStep(x_ticks)); },
      [&](double t) { return TickText(t, TickStep(y_ticks)); }, x_label, kDisplay[output].unit);
  for (size_t l = 0; l < lines.size(); ++l) {
    const Line& line = lines[l];
    const char* colour = kColours[l % kMaxSeries];
    std::string data_runs, data_values, d;
    bool pen_down = false;
    for (size_t i = 0; i < line.runs.size(); ++i) {
      const SweepRun& run = runs[line.runs[i]];
      const double v = run.ok() ? run.outputs.*field : NAN;
      data_runs += (i ? " " : "") + std::to_string(run.index);
      data_values += (i ? " " : "") + Num(v);
      if (!std::isfinite(v)) {
        pen_down = false;
        continue;
      }
      d += (pen_down ? "L" : "M") + Fixed(px(x_values[i]), 1) + "," + Fixed(py(v * scale), 1) + " ";
      pen_down = true;
    }
    o << "<path data-series=\"" << Escape(line.name) << "\" data-runs=\"" << data_runs
      << "\" data-values=\"" << data_values << "\" fill=\"none\" stroke=\"" << colour
      << "\" stroke-width=\"1.8\" d=\"" << d << "\"/>\n";
    for (size_t i = 0; i < line.runs.size(); ++i) {
      const SweepRun& run = runs[line.runs[i]];
      const double x = px(x_values[i]);
      if (run.ok() && std::isfinite(run.outputs.*field)) {
        o << "<circle cx=\"" << Fixed(x, 1) << "\" cy=\""
          << Fixed(py(run.outputs.*field * scale), 1) << "\" r=\"3.2\" fill=\"" << colour
          << "\"><title>run " << run.index << ": " << Short(run.outputs.*field * scale) << " "
          << kDisplay[output].unit << "</title></circle>";
      } else if (!run.ok()) {
        const double y = kFrame.height - kFrame.bottom - 6;
        o << "<path class=\"failed\" d=\"M" << Fixed(x - 5, 1) << "," << Fixed(y - 5, 1) << " L"
          << Fixed(x + 5, 1) << "," << Fixed(y + 5, 1) << " M" << Fixed(x - 5, 1) << ","
          << Fixed(y + 5, 1) << " L" << Fixed(x + 5, 1) << "," << Fixed(y - 5, 1)
          << "\"><title>run " << run.index << " " << StatusName(run.status) << "</title></path>";
      }
    }
    o << "\n";
  }
  o << "</svg>\n";
  return o.str();
}

// "" when the output varies over the finished runs; else what a reader should be told instead of
// a flat plot.
std::string SameInEveryRun(const std::vector<SweepRun>& runs, size_t output) {
  const auto field = kSweepOutputs[output].field;
  double lo = INFINITY, hi = -INFINITY;
  int finite = 0;
  for (const SweepRun& run : runs) {
    const double v = run.outputs.*field;
    if (!run.ok() || !std::isfinite(v)) continue;
    ++finite;
    lo = std::min(lo, v);
    hi = std::max(hi, v);
  }
  if (finite == 0) return "Undefined in every run (no net, or no run finished).";
  if (lo != hi) return "";
  const std::string value = Short(lo * kDisplay[output].scale) + " " + kDisplay[output].unit;
  if (output == 2 && lo == 0) return "No run touched a body: 0 in every run.";
  bool first_frame = true;  // the area largest at t = 0 in every finished run
  for (const SweepRun& run : runs)
    if (run.ok()) first_frame = first_frame && run.outputs.max_area_time_s == 0.0;
  if ((output == 0 || output == 1) && first_frame)
    return value +
           " in every run: the net is largest in its first frame (it starts spread and "
           "never opens wider).";
  return value + " in every run.";
}

void WriteHead(std::ostringstream& o, const std::string& title) {
  o << "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\n"
    << "<title>netlab sweep: " << Escape(title) << "</title>\n<style>\n"
    << "body{font-family:system-ui,sans-serif;max-width:1180px;margin:24px auto;padding:0 16px;"
       "color:#222}\n"
    << "h1{font-size:22px;margin:0 0 4px}h2{font-size:17px;margin:28px 0 4px}"
       "h3{font-size:14px;margin:10px 0 2px;font-weight:600}\n"
    << ".files{color:#666;font-size:13px}.verdict{font-size:20px;padding:12px 16px;"
       "border-radius:6px;margin:16px 0}\n"
    << ".ok{background:#e3f4e8;border-left:6px solid #009e73}.bad{background:#fbe6dc;"
       "border-left:6px solid #d55e00}\n"
    << ".numbers{display:grid;grid-template-columns:repeat(4,1fr);gap:8px;margin:12px 0}\n"
    << ".numbers div{background:#f4f4f4;border-radius:6px;padding:8px 12px}.numbers b{display:"
       "block;font-size:20px}\n"
    << ".plots{display:grid;grid-template-columns:repeat(auto-fill,minmax(400px,1fr));gap:10px}"
       ".caption{font-size:13px;color:#444;max-width:900px}\n"
    << "svg.plot{font-size:11px;background:#fff}svg .grid{stroke:#e4e4e4}svg .frame{fill:none;"
       "stroke:#888}svg .label{font-size:12px;fill:#333}svg .failed{stroke:#d00;stroke-width:2;"
       "fill:none}\n"
    << "table{border-collapse:collapse;font-size:13px}td,th{border-bottom:1px solid #ddd;"
       "padding:3px 10px;text-align:right}th{background:#f4f4f4}td:first-child,th:first-child"
       "{text-align:left}\n"
    << "td.strong{font-weight:700}td.none{color:#999}code{font-size:12px}\n"
    << ".legend{font-size:13px;margin:4px 0}.legend span{display:inline-block;margin-right:18px}"
       ".legend i{display:inline-block;width:22px;height:3px;vertical-align:middle;"
       "margin-right:6px}\n"
    << ".notes{background:#fff8e1;padding:8px 16px;border-radius:6px;font-size:13px}\n"
    << "</style></head><body>\n";
}

void WriteSummary(std::ostringstream& o, const std::vector<SweepParameter>& parameters,
                  const SweepResult& result, const SweepReportInfo& info) {
  const int total = static_cast<int>(result.runs.size()), failed = result.failed();
  o << "<h1>netlab sweep</h1>\n<div class=\"files\">scenario: " << Escape(info.scenario_path);
  for (const ScenarioOverride& f : info.fixed) o << " --set " << Escape(f.Text());
  o << " &nbsp; data: " << Escape(info.sweep_path) << "</div>\n";
  o << "<div class=\"verdict " << (failed == 0 ? "ok" : "bad") << "\"><b>" << total - failed
    << " of " << total << " runs finished</b>"
    << (failed == 0 ? ", none failed."
                    : "; " + std::to_string(failed) +
                          " failed (listed below, left out of the "
                          "lines and the sensitivities).")
    << "</div>\n";
  int parameters_varied = 0;
  for (const SweepParameter& p : parameters) parameters_varied += p.count > 1;
  o << "<div class=\"numbers\"><div>runs<b>" << total << "</b>" << parameters_varied << " parameter"
    << (parameters_varied == 1 ? "" : "s") << " varied</div>"
    << "<div>wall time<b>" << Fixed(result.wall_s, 1) << " s</b>" << Fixed(result.RunsPerHour(), 0)
    << " runs/hour</div>"
    << "<div>workers<b>" << result.jobs * result.ranks << "</b>" << result.ranks << " process"
    << (result.ranks == 1 ? "" : "es (MPI ranks)") << " × " << result.jobs << " thread"
    << (result.jobs == 1 ? "" : "s") << "</div>"
    << "<div>simulated per run<b>"
    << Fixed(result.runs.empty() ? NAN : result.runs.front().summary.sim_time, 3)
    << " s</b>of the scene (the first run)</div></div>\n";
  o << "<h2>Parameters</h2>\n<table>" << Row({"parameter (--vary)", "from", "to", "values"}, "th");
  for (const SweepParameter& p : parameters) {
    std::string values;
    for (double v : p.Values()) values += (values.empty() ? "" : ", ") + Short(v);
    o << Row({"<code>" + Escape(p.path) + "</code>", Short(p.from), Short(p.to), values});
  }
  o << "</table>\n<p class=\"caption\">Values in the scenario's units at that path "
       "(docs/scenarios.md); every run is the scenario with one value of each.</p>\n";
}

void WriteSensitivity(std::ostringstream& o, const std::vector<SweepParameter>& parameters,
                      const std::vector<std::vector<Sensitivity>>& sensitivity) {
  o << "<h2>Sensitivities d ln(output) / d ln(parameter)</h2>\n<table id=\"sensitivity\">";
  std::vector<std::string> head = {"output"};
  for (const SweepParameter& p : parameters) head.push_back("<code>" + Escape(p.path) + "</code>");
  o << Row(head, "th");
  for (size_t out = 0; out < kSweepOutputs.size(); ++out) {
    o << "<tr><td>" << kSweepOutputs[out].title << " (" << kDisplay[out].unit << ")</td>";
    for (size_t q = 0; q < parameters.size(); ++q) {
      const Sensitivity& s = sensitivity[out][q];
      if (std::isfinite(s.value))
        o << "<td data-value=\"" << Num(s.value) << "\""
          << (std::abs(s.value) >= 0.5 ? " class=\"strong\"" : "") << " title=\"runs " << s.run_low
          << " and " << s.run_high << "\">"
          << (s.value != 0 && std::abs(s.value) < 5e-4 ? Num(s.value, 2) : Fixed(s.value, 3))
          << "</td>";
      else
        o << "<td data-value=\"nan\" class=\"none\">– (" << Escape(s.why_not) << ")</td>";
    }
    o << "</tr>\n";
  }
  o << "</table>\n<p class=\"caption\">How strongly each output answers each parameter: "
       "S = (p / o) ∂o/∂p, so a 1 % larger parameter changes the output by about S % (0: no "
       "effect, 1: proportional, negative: the output falls). Each S is a central difference at "
       "the centre of the grid: the two runs either side of the parameter's middle value (the two "
       "middle runs for an even count, the whole range for 2 values), every other parameter at "
       "its middle value; p and o are taken at the middle. |S| ≥ 0.5 in bold. Hover a number for "
       "the runs it uses. A difference over a wide range averages a curved response: read it "
       "with the plots below.</p>\n";
}

void WritePlots(std::ostringstream& o, const std::vector<SweepParameter>& parameters,
                const SweepResult& result) {
  for (size_t q = 0; q < parameters.size(); ++q) {
    const SweepParameter& p = parameters[q];
    if (p.count < 2) continue;
    const std::vector<Line> lines = LinesAlong(parameters, q);
    o << "<h2>Against <code>" << Escape(p.path) << "</code></h2>\n";
    if (lines.size() > 1 || !lines[0].name.empty()) {
      o << "<div class=\"legend\">";
      for (size_t l = 0; l < lines.size(); ++l)
        o << "<span><i style=\"background:" << kColours[l % kMaxSeries] << "\"></i>"
          << Escape(lines[l].name) << "</span>";
      o << "</div>\n";
    }
    o << "<div class=\"plots\">";
    for (size_t out = 0; out < kSweepOutputs.size(); ++out) {
      // An output that is the same in every run (no contact; a net largest in its first frame)
      // gets a sentence, not a flat line.
      const std::string same = SameInEveryRun(result.runs, out);
      if (!same.empty()) {
        o << "<div><h3>" << kSweepOutputs[out].title << "</h3><p class=\"caption\">" << same
          << "</p></div>\n";
        continue;
      }
      o << "<div><h3>" << kSweepOutputs[out].title << "</h3>\n"
        << Plot(std::string(kSweepOutputs[out].name) + "-vs-" + std::to_string(q), p.Values(),
                lines, result.runs, out, p.path)
        << "</div>\n";
    }
    o << "</div>\n";
  }
  o << "<p class=\"caption\">One dot per finished run; a red × on the bottom edge marks a run that "
       "failed at that value. Lines join the runs that differ only in the parameter on the axis "
       "(one line per combination of the others' values, up to "
    << kMaxSeries
    << "; beyond that the line through their middle values). Opening area: the "
       "corner polygon of net 0, largest over the run; drift: how far the knots' centroid moved "
       "from the first output frame to the last.</p>\n";
}

void WriteRuns(std::ostringstream& o, const std::vector<SweepParameter>& parameters,
               const std::vector<SweepPoint>& grid, const SweepResult& result) {
  const int failed = result.failed();
  if (failed > 0) {
    o << "<h2>Failed runs</h2>\n<div class=\"notes\"><ul>";
    for (const SweepRun& run : result.runs) {
      if (run.ok()) continue;
      // The values it ran with (4 digits; /runs/overrides in sweep.h5 has them exactly).
      std::string values;
      for (size_t q = 0; q < parameters.size(); ++q)
        values += (q ? ", " : "") + parameters[q].path + " = " + Short(grid[run.index].values[q]);
      o << "<li>run " << run.index << " (" << Escape(values) << "), " << StatusName(run.status)
        << ": " << Escape(run.error) << "</li>";
    }
    o << "</ul></div>\n";
  }
  o << "<h2>Every run</h2>\n<table id=\"runs\">";
  std::vector<std::string> head = {"run"};
  for (const SweepParameter& p : parameters)
    head.push_back("<code title=\"" + Escape(p.path) + "\">" + Escape(ShortName(p.path)) +
                   "</code>");
  for (size_t out = 0; out < kSweepOutputs.size(); ++out)
    head.push_back(std::string(kSweepOutputs[out].name) + " (" + kDisplay[out].unit + ")");
  head.push_back("wall (s)");
  head.push_back("status");
  o << Row(head, "th");
  for (const SweepRun& run : result.runs) {
    std::vector<std::string> cells = {std::to_string(run.index)};
    for (double v : grid[run.index].values) cells.push_back(Short(v));
    for (size_t out = 0; out < kSweepOutputs.size(); ++out)
      cells.push_back(run.ok() ? Num(run.outputs.*kSweepOutputs[out].field * kDisplay[out].scale, 6)
                               : "–");
    cells.push_back(Fixed(run.summary.wall_s, 2));
    cells.push_back(StatusName(run.status));
    o << Row(cells);
  }
  o << "</table>\n";
}

}  // namespace

std::string SweepReportHtml(const std::vector<SweepParameter>& parameters,
                            const std::vector<SweepPoint>& grid, const SweepResult& result,
                            const std::vector<std::vector<Sensitivity>>& sensitivity,
                            const SweepReportInfo& info) {
  std::ostringstream o;
  std::string title;
  for (const SweepParameter& p : parameters)
    title += (title.empty() ? "" : ", ") + ShortName(p.path);
  WriteHead(o, title);
  WriteSummary(o, parameters, result, info);
  WriteSensitivity(o, parameters, sensitivity);
  WritePlots(o, parameters, result);
  WriteRuns(o, parameters, grid, result);
  o << "</body></html>\n";
  return o.str();
}

void WriteSweepReport(const std::string& path, const std::vector<SweepParameter>& parameters,
                      const std::vector<SweepPoint>& grid, const SweepResult& result,
                      const std::vector<std::vector<Sensitivity>>& sensitivity,
                      const SweepReportInfo& info) {
  WriteTextFile(path, SweepReportHtml(parameters, grid, result, sensitivity, info));
}

}  // namespace netlab::netsim
