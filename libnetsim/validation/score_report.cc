#include "libnetsim/validation/score_report.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <sstream>
#include <stdexcept>

#include "common/files.h"
#include "common/html.h"
#include "libnetsim/validation/repeats.h"

namespace netlab::netsim {
namespace {

using html::Escape;
using html::Fixed;
using html::Num;
using html::Row;
using html::Ticks;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
// Colours that stay apart for colour-blind readers (Okabe-Ito).
constexpr const char* kClassColours[3] = {"#d55e00", "#0072b2", "#009e73"};

std::string Values(const std::vector<double>& v) {
  std::string s;
  for (size_t i = 0; i < v.size(); ++i) {
    if (i) s += ' ';
    s += Num(v[i]);
  }
  return s;
}

// A line plot in SVG: axes with round ticks, series as paths broken where a value is NaN.
class LinePlot {
 public:
  struct Series {
    std::string name, colour;
    std::vector<double> x, y;  // plotted (display units)
    std::vector<double> data;  // as in score.h5 (data-values)
    bool dashed = false;
  };

  void Add(Series s) { series_.push_back(std::move(s)); }

  std::string Svg(const std::string& id, const std::string& x_label, const std::string& y_label,
                  const std::vector<double>& times, bool y_from_zero = true) const {
    double x0 = INFINITY, x1 = -INFINITY, y0 = y_from_zero ? 0.0 : INFINITY, y1 = -INFINITY;
    for (const auto& s : series_)
      for (size_t i = 0; i < s.x.size(); ++i)
        if (std::isfinite(s.y[i]) && std::isfinite(s.x[i])) {
          x0 = std::min(x0, s.x[i]);
          x1 = std::max(x1, s.x[i]);
          y0 = std::min(y0, s.y[i]);
          y1 = std::max(y1, s.y[i]);
        }
    if (!std::isfinite(x0)) x0 = 0, x1 = 1, y0 = 0, y1 = 1;
    if (x1 <= x0) x1 = x0 + 1;
    if (y1 <= y0) y1 = y0 + 1;
    y1 += 0.05 * (y1 - y0);
    auto px = [&](double x) { return kFrame.X(x, x0, x1); };
    auto py = [&](double y) { return kFrame.Y(y, y0, y1); };
    std::ostringstream o;
    o << "<svg id=\"" << id << "\" class=\"plot\" viewBox=\"0 0 " << kFrame.width << " "
      << kFrame.height << "\" width=\"" << kFrame.width << "\" height=\"" << kFrame.height
      << "\" data-times=\"" << Values(times) << "\">\n";
    Axes(o, x0, x1, y0, y1, x_label, y_label);
    for (const auto& s : series_) {
      o << "<path data-series=\"" << s.name << "\" data-values=\"" << Values(s.data)
        << "\" fill=\"none\" stroke=\"" << s.colour << "\" stroke-width=\"1.8\""
        << (s.dashed ? " stroke-dasharray=\"6 4\"" : "") << " d=\"";
      bool pen_down = false;
      for (size_t i = 0; i < s.x.size(); ++i) {
        if (!std::isfinite(s.y[i])) {
          pen_down = false;
          continue;
        }
        o << (pen_down ? "L" : "M") << Fixed(px(s.x[i]), 1) << "," << Fixed(py(s.y[i]), 1) << " ";
        pen_down = true;
      }
      o << "\"/>\n";
    }
    Legend(o);
    o << "</svg>\n";
    return o.str();
  }

  static constexpr html::PlotFrame kFrame{};

  // The axes over [x0, x1] x [y0, y1]: about five y ticks and six x ticks, four digits each.
  static void Axes(std::ostream& o, double x0, double x1, double y0, double y1,
                   const std::string& x_label, const std::string& y_label) {
    const auto text = [](double t) { return Num(t, 4); };
    html::PlotAxes(o, kFrame, x0, x1, y0, y1, Ticks(x0, x1, 6), Ticks(y0, y1), text, text, x_label,
                   y_label);
  }

 private:
  void Legend(std::ostringstream& o) const {
    double x = kFrame.left + 12;
    for (const auto& s : series_) {
      o << "<line x1=\"" << x << "\" x2=\"" << x + 22 << "\" y1=\"" << kFrame.top - 14 << "\" y2=\""
        << kFrame.top - 14 << "\" stroke=\"" << s.colour << "\" stroke-width=\"3\""
        << (s.dashed ? " stroke-dasharray=\"6 4\"" : "") << "/><text x=\"" << x + 27 << "\" y=\""
        << kFrame.top - 10 << "\">" << s.name << "</text>\n";
      x += 40 + 8 * s.name.size();
    }
  }

  std::vector<Series> series_;
};

// Light yellow (small) to dark red (large), for the per-knot map.
std::string Heat(double f) {
  static const double stops[5][3] = {
      {255, 255, 204}, {254, 217, 118}, {253, 141, 60}, {227, 26, 28}, {128, 0, 38}};
  f = std::clamp(f, 0.0, 1.0) * 4;
  const int i = std::min(3, static_cast<int>(f));
  const double w = f - i;
  char buffer[16];
  std::snprintf(buffer, sizeof(buffer), "#%02x%02x%02x",
                static_cast<int>(stops[i][0] * (1 - w) + stops[i + 1][0] * w),
                static_cast<int>(stops[i][1] * (1 - w) + stops[i + 1][1] * w),
                static_cast<int>(stops[i][2] * (1 - w) + stops[i + 1][2] * w));
  return buffer;
}

// The corner-polygon plot's caption: the largest area measured and simulated, and when; or why
// there is no measured curve (the polygon needs all four corners in a frame).
std::string AreaCaption(const ScoreResult& r) {
  const ScoreSummary& s = r.summary;
  int measured = 0;
  for (double a : r.area_measured) measured += std::isfinite(a);
  std::string text = measured == 0 ? "Measured: none (no frame has all four corners measured). "
                                   : "Maximum measured " + Fixed(s.max_area_measured_m2, 3) +
                                         " m² at " + Fixed(s.max_area_time_measured_s, 3) + " s, ";
  text += (measured == 0 ? "Simulated: maximum " : "simulated ") +
          Fixed(s.max_area_simulated_m2, 3) + " m² at " + Fixed(s.max_area_time_simulated_s, 3) +
          " s.";
  return text;
}

std::string KnotMap(const ScoreResult& r) {
  const ScoreSummary& s = r.summary;
  int rows = 0, cols = 0;
  for (const auto& g : r.grid) rows = std::max(rows, g[0] + 1), cols = std::max(cols, g[1] + 1);
  double top = 0;
  std::vector<double> values;
  for (const auto& row : s.per_knot) {
    values.push_back(row.rms_m);
    if (std::isfinite(row.rms_m)) top = std::max(top, row.rms_m * 1e3);
  }
  if (top <= 0) top = 1;
  const double cell = std::min(34.0, 360.0 / std::max(rows, cols));
  const double left = 44, upper = 30, bar_x = left + cols * cell + 30;
  const double width = bar_x + 90, height = std::max(upper + rows * cell + 40, 260.0);
  std::ostringstream o;
  o << "<svg id=\"knot-map\" class=\"plot\" viewBox=\"0 0 " << width << " " << height
    << "\" width=\"" << width << "\" height=\"" << height << "\" data-values=\"" << Values(values)
    << "\">\n";
  o << "<text x=\"" << left + cols * cell / 2 << "\" y=\"14\" text-anchor=\"middle\" "
    << "class=\"label\">column →</text>\n";
  o << "<text transform=\"translate(14," << upper + rows * cell / 2
    << ") rotate(-90)\" text-anchor=\"middle\" class=\"label\">← row</text>\n";
  for (size_t k = 0; k < r.grid.size(); ++k) {
    const double v = s.per_knot[k].rms_m * 1e3;
    const double x = left + r.grid[k][1] * cell, y = upper + r.grid[k][0] * cell;
    o << "<rect data-knot=\"(" << r.grid[k][0] << "," << r.grid[k][1] << ")\" data-value=\""
      << Num(s.per_knot[k].rms_m) << "\" x=\"" << x << "\" y=\"" << y << "\" width=\"" << cell - 1
      << "\" height=\"" << cell - 1 << "\" fill=\""
      << (std::isfinite(v) ? Heat(v / top) : std::string("#bbbbbb")) << "\"><title>knot ("
      << r.grid[k][0] << "," << r.grid[k][1] << "): " << Fixed(v, 2) << " mm RMS, mean d² "
      << Fixed(s.per_knot[k].mean_d2, 2) << ", " << s.per_knot[k].points
      << " frames</title></rect>\n";
  }
  // Row and column numbers every few knots.
  const int every = std::max(1, (std::max(rows, cols) + 5) / 6);
  for (int c = 0; c < cols; c += every)
    o << "<text x=\"" << left + (c + 0.5) * cell << "\" y=\"" << upper - 4
      << "\" text-anchor=\"middle\">" << c << "</text>";
  for (int row = 0; row < rows; row += every)
    o << "<text x=\"" << left - 4 << "\" y=\"" << upper + (row + 0.5) * cell + 4
      << "\" text-anchor=\"end\">" << row << "</text>";
  o << "\n";
  // The colour bar, 0 .. the worst knot.
  const double bar_h = rows * cell;
  for (int i = 0; i < 40; ++i)
    o << "<rect x=\"" << bar_x << "\" y=\"" << Fixed(upper + bar_h * (1 - (i + 1) / 40.0), 2)
      << "\" width=\"16\" height=\"" << Fixed(bar_h / 40 + 0.5, 2) << "\" fill=\""
      << Heat((i + 0.5) / 40) << "\"/>";
  o << "\n";
  for (double t : Ticks(0, top, 4))
    o << "<text x=\"" << bar_x + 22 << "\" y=\"" << Fixed(upper + bar_h * (1 - t / top) + 4, 1)
      << "\">" << Num(t, 3) << "</text>";
  o << "<text x=\"" << bar_x - 6 << "\" y=\"" << upper + bar_h + 22
    << "\" class=\"label\">RMS mm</text>\n</svg>\n";
  return o.str();
}

std::string Histogram(const ScoreResult& r) {
  const html::PlotFrame& frame = LinePlot::kFrame;
  const double w = frame.width, h = frame.height, left = frame.left, top = frame.top;
  const size_t bins = r.d2_counts.size();
  double y1 = 1;
  for (size_t b = 0; b < bins; ++b) y1 = std::max({y1, r.d2_counts[b], r.d2_expected[b]});
  y1 *= 1.05;
  const double x0 = 0, x1 = r.d2_edges.empty() ? 1 : r.d2_edges.back();
  auto px = [&](double x) { return frame.X(x, x0, x1); };
  auto py = [&](double y) { return frame.Y(y, 0, y1); };
  std::ostringstream o;
  o << "<svg id=\"d2-histogram\" class=\"plot\" viewBox=\"0 0 " << w << " " << h << "\" width=\""
    << w << "\" height=\"" << h << "\">\n";
  LinePlot::Axes(o, x0, x1, 0, y1, "d² (the last bin holds everything above)",
                 "knot-frames per bin");
  o << "<g data-series=\"counts\" data-values=\"" << Values(r.d2_counts) << "\" fill=\"#56b4e9\">";
  for (size_t b = 0; b < bins; ++b)
    o << "<rect x=\"" << Fixed(px(r.d2_edges[b]) + 0.5, 1) << "\" y=\""
      << Fixed(py(r.d2_counts[b]), 1) << "\" width=\""
      << Fixed(px(r.d2_edges[b + 1]) - px(r.d2_edges[b]) - 1, 1) << "\" height=\""
      << Fixed(py(0) - py(r.d2_counts[b]), 1) << "\"/>";
  o << "</g>\n<path data-series=\"expected\" data-values=\"" << Values(r.d2_expected)
    << "\" fill=\"none\" stroke=\"#000\" stroke-width=\"2\" d=\"";
  for (size_t b = 0; b < bins; ++b)
    o << (b ? "L" : "M") << Fixed(px(0.5 * (r.d2_edges[b] + r.d2_edges[b + 1])), 1) << ","
      << Fixed(py(r.d2_expected[b]), 1) << " ";
  o << "\"/>\n";
  const double lx = left + 12;
  o << "<rect x=\"" << lx << "\" y=\"" << top - 19 << "\" width=\"14\" height=\"10\" "
    << "fill=\"#56b4e9\"/><text x=\"" << lx + 20 << "\" y=\"" << top - 10
    << "\">measured d²</text><line x1=\"" << lx + 130 << "\" x2=\"" << lx + 152 << "\" y1=\""
    << top - 14 << "\" y2=\"" << top - 14 << "\" stroke=\"#000\" stroke-width=\"2\"/><text x=\""
    << lx + 157 << "\" y=\"" << top - 10 << "\">χ²₃: expected if consistent</text>\n</svg>\n";
  return o.str();
}

// The document's head (title, inline style) and the opening of its body.
void WriteHead(std::ostringstream& o, const ScoreSummary& s) {
  o << "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\n"
    << "<title>netlab score: " << Escape(VerdictName(s.verdict)) << "</title>\n<style>\n"
    << "body{font-family:system-ui,sans-serif;max-width:1180px;margin:24px auto;padding:0 16px;"
       "color:#222}\n"
    << "h1{font-size:22px;margin:0 0 4px}h2{font-size:17px;margin:28px 0 4px}\n"
    << ".files{color:#666;font-size:13px}.verdict{font-size:20px;padding:12px 16px;"
       "border-radius:6px;margin:16px 0}\n"
    << ".ok{background:#e3f4e8;border-left:6px solid #009e73}.bad{background:#fbe6dc;"
       "border-left:6px solid #d55e00}\n"
    << ".numbers{display:grid;grid-template-columns:repeat(5,1fr);gap:8px;margin:12px 0}\n"
    << ".numbers div{background:#f4f4f4;border-radius:6px;padding:8px 12px}.numbers b{display:"
       "block;font-size:20px}\n"
    << ".grid2{display:grid;grid-template-columns:1fr 1fr;gap:18px}.caption{font-size:13px;"
       "color:#444;max-width:560px}\n"
    << "svg.plot{font-size:11px;background:#fff}svg .grid{stroke:#e4e4e4}svg .frame{fill:none;"
       "stroke:#888}svg .label{font-size:12px;fill:#333}\n"
    << "table{border-collapse:collapse;font-size:13px}td,th{border-bottom:1px solid #ddd;"
       "padding:3px 10px;text-align:right}th{background:#f4f4f4}td:first-child{text-align:left}\n"
    << ".notes{background:#fff8e1;padding:8px 16px;border-radius:6px;font-size:13px}\n"
    << ".headline{font-size:15px;margin:8px 0}\n"
    << "</style></head><body>\n";
}

// The title and the files, the verdict, the few numbers that decide it and how to read them.
void WriteVerdict(std::ostringstream& o, const ScoreSummary& s, const ReportInfo& info) {
  const bool ok = s.verdict == Verdict::kConsistent;
  o << "<h1>netlab score</h1>\n<div class=\"files\">measured: " << Escape(info.measured_path)
    << " &nbsp; simulation: " << Escape(info.sim_path)
    << " &nbsp; data: " << Escape(info.score_path) << "</div>\n";
  o << "<div class=\"verdict " << (ok ? "ok" : "bad") << "\"><b>"
    << (ok ? "Consistent" : "Not consistent")
    << "</b> with the measurement uncertainty: mean d² = " << Fixed(s.mean_d2, 2)
    << " where 3 is expected; the test rejects above " << Fixed(s.critical_mean_d2, 2)
    << " (p = " << Num(s.p_value, 3) << ").</div>\n";
  const int informative = s.points - s.left_out;
  o << "<div class=\"numbers\">"
    << "<div>RMS error<b>" << Fixed(s.rms_m * 1e3, 2) << " mm</b>"
    << Fixed(s.rms_percent_of_side, 2) << " % of the " << Fixed(s.side_m, 2) << " m side</div>"
    << "<div>largest error<b>" << Fixed(s.max_m * 1e3, 2) << " mm</b>over " << informative
    << " knot-frames" << (s.left_out > 0 ? " (" + std::to_string(s.left_out) + " left out)" : "")
    << "</div>"
    << "<div>covariance-weighted RMS<b>" << Fixed(s.weighted_rms_m * 1e3, 2)
    << " mm</b>each point weighed by 1 / its variance</div>"
    << "<div>time offset<b>" << Fixed(s.time_offset_s * 1e3, 3) << " ms</b>± "
    << Fixed(s.time_offset_sigma_s * 1e3, 3) << " ms (t_sim = t_measured + offset)</div>"
    << "<div>skill<b>" << Fixed(s.skill, 3) << "</b>1 = perfect, 0 = no better than straight-line "
    << "flight (" << Fixed(s.baseline_rms_m * 1e3, 1) << " mm)</div></div>\n";
  o << "<p class=\"headline\">" << Escape(s.headline) << "</p>\n";
  o << "<p class=\"caption\">d² is each knot's squared error in units of its measurement "
       "covariance (Σ_sim: "
    << Escape(s.sim_uncertainty) << "); about 3 on average when the simulation is right. "
    << s.frames << " frames × " << s.knots << " knots, " << s.masked
    << " knot-frames masked (not measured"
    << (s.degenerate > 0 ? ", " + std::to_string(s.degenerate) + " of them degenerate" : "")
    << "). Errors are correlated in time (τ_int " << Fixed(s.tau_int, 1)
    << " frames) and across a frame's knots (×" << Fixed(s.design_effect, 2)
    << "): the test counts " << Fixed(s.effective_points, 0) << " independent points.</p>\n";
}

// What a reader must know, when there is anything.
void WriteNotes(std::ostringstream& o, const ScoreSummary& s) {
  if (s.notes.empty()) return;
  o << "<div class=\"notes\"><b>Notes</b><ul>";
  for (const auto& n : s.notes) o << "<li>" << Escape(n) << "</li>";
  o << "</ul></div>\n";
}

// Error vs time per class: each class's RMS error per frame, plotted in mm, its data in m.
LinePlot ErrorVsTimePlot(const ScoreResult& r) {
  LinePlot evt;
  for (int c = 0; c < 3; ++c) {
    LinePlot::Series series{kKnotClassNames[c], kClassColours[c], r.time, {}, {}};
    for (const auto& v : r.rms_per_class) {
      series.data.push_back(v[c]);
      series.y.push_back(v[c] * 1e3);
    }
    evt.Add(series);
  }
  return evt;
}

// Corner-polygon area, measured (solid) and simulated (dashed).
LinePlot CornerAreaPlot(const ScoreResult& r) {
  LinePlot area;
  LinePlot::Series measured{"measured", "#000000", r.time, {}, r.area_measured};
  LinePlot::Series simulated{"simulated", "#cc79a7", r.time, {}, r.area_simulated, true};
  measured.y = r.area_measured;
  simulated.y = r.area_simulated;
  area.Add(measured);
  area.Add(simulated);
  return area;
}

// The four plots, two by two, each with its caption.
void WritePlots(std::ostringstream& o, const ScoreResult& r) {
  o << "<div class=\"grid2\"><div><h2>Error over time, per knot class</h2>\n"
    << ErrorVsTimePlot(r).Svg("error-vs-time", "measured time (s)", "RMS error (mm)", r.time)
    << "<div class=\"caption\">RMS distance between measured and simulated knots in each frame; "
       "corners carry the masses and lead the net, edges and the inner knots follow.</div></div>\n";
  o << "<div><h2>Error per knot</h2>\n"
    << KnotMap(r)
    << "<div class=\"caption\">Each square is a knot of the net, placed by its grid (row, col), "
       "coloured by its RMS error over all frames (hover for the numbers; grey: never measured)."
       "</div></div>\n";
  o << "<div><h2>Opening of the net: corner-polygon area</h2>\n"
    << CornerAreaPlot(r).Svg("corner-area", "measured time (s)", "area (m²)", r.time, false)
    << "<div class=\"caption\">Area spanned by the four corner knots. " << AreaCaption(r)
    << "</div></div>\n";
  o << "<div><h2>d² against its expectation</h2>\n"
    << Histogram(r)
    << "<div class=\"caption\">If the simulation is right and the covariances are honest, the "
       "bars follow the black curve (χ² with 3 degrees of freedom). Bars piled up on the right: "
       "errors larger than the measurement explains.</div></div></div>\n";
}

// Tables: per knot class and per phase, with how the phases were cut.
void WriteClassAndPhaseTables(std::ostringstream& o, const ScoreSummary& s) {
  o << "<h2>Per knot class and per phase</h2>\n<table>"
    << Row({"", "knot-frames", "RMS (mm)", "max (mm)", "mean d²", "from (s)", "to (s)"}, "th");
  for (const auto& row : s.per_class)
    o << Row({row.name, std::to_string(row.points), Fixed(row.rms_m * 1e3, 2),
              Fixed(row.max_m * 1e3, 2), Fixed(row.mean_d2, 2), "", ""});
  for (const auto& row : s.per_phase)
    o << Row({"phase: " + row.name, std::to_string(row.points), Fixed(row.rms_m * 1e3, 2),
              Fixed(row.max_m * 1e3, 2), Fixed(row.mean_d2, 2), Fixed(row.start_s, 3),
              Fixed(row.end_s, 3)});
  const std::string contact = s.contact_from == ContactFrom::kGiven
                                  ? "contact from the given time of first contact"
                              : s.contact_from == ContactFrom::kSimulation
                                  ? "contact from the simulation's first contact with the "
                                    "target (" +
                                        Fixed(s.contact_time_s, 3) + " s simulated)"
                                  : "no contact phase (the simulation has no contact)";
  o << "</table>\n<p class=\"caption\">Phases from the simulated corner polygon: ejection until "
       "it reaches half its largest area, spreading until the largest, opened after it; "
    << contact << ". Phases the measurement does not reach have no knot-frames.</p>\n";
  // Per phase, the two contributions to the expected error beside the error itself.
  o << "<h3>Per phase: the error and what it is weighed against</h3>\n<table>"
    << Row({"phase", "RMS error (mm)", "σ simulation (mm)", "σ measurement (mm)", "mean d²"}, "th");
  for (const auto& row : s.per_phase)
    o << Row({row.name, Fixed(row.rms_m * 1e3, 2), Fixed(row.sigma_sim_m * 1e3, 2),
              Fixed(row.sigma_meas_m * 1e3, 2), Fixed(row.mean_d2, 2)});
  o << "</table>\n<p class=\"caption\">σ: the square root of the mean trace of each covariance "
       "over the phase's compared knot-frames (the RMS length of the error each alone would "
       "explain). The simulation's is "
    << Escape(s.sim_uncertainty)
    << (s.ensemble_members > 0 ? ": large in a phase where the model's own runs part" : "")
    << ".</p>\n";
}

// The alignment's table: what was fitted, the fit, and the simulation's sampling.
void WriteAlignmentTable(std::ostringstream& o, const ScoreSummary& s) {
  o << "<h2>Alignment (" << AlignmentName(s.alignment) << ")</h2>\n<table>"
    << Row({"fitted parameters", std::to_string(s.fitted_parameters)})
    << Row({"time offset (ms)",
            Fixed(s.time_offset_s * 1e3, 3) + " ± " + Fixed(s.time_offset_sigma_s * 1e3, 3)})
    << Row({"translation meas_from_sim (mm)", Fixed(s.translation.x() * 1e3, 2) + ", " +
                                                  Fixed(s.translation.y() * 1e3, 2) + ", " +
                                                  Fixed(s.translation.z() * 1e3, 2)})
    << Row({"rotation angle (deg)",
            Fixed(std::acos(std::clamp((s.rotation.trace() - 1) / 2, -1.0, 1.0)) * 180 / M_PI, 4)})
    << Row({"simulation stored every (ms)", Fixed(s.sim_interval_s * 1e3, 3)})
    << Row({"interpolation error (mm RMS)", Fixed(s.interpolation_rms_m * 1e3, 4)})
    << Row({"degrees of freedom", Num(s.dof, 8)}) << "</table>\n";
}

// Repeats: one row per shot, the pooled test, and the spread between the shots beside the
// model's error, per phase and per knot class.
void WriteRepeats(std::ostringstream& o, const RepeatsResult& repeats) {
  const RepeatsSummary& r = repeats.summary;
  o << "<h2 id=\"repeats\">Repeats</h2>\n<p class=\"caption\">" << repeats.shots.size()
    << " shots of the case, each scored on its own (its own time offset"
    << (repeats.shots[0].summary.alignment == Alignment::kRigid ||
                repeats.shots[0].summary.alignment == Alignment::kTimeAndRigid
            ? " and rigid alignment"
            : "")
    << "); the verdict above pools their tests by Fisher's method, −2 Σ ln p over the shots "
       "against χ² of twice as many degrees of freedom as shots: a shot the model misses "
       "rejects the pool however well the others fit.</p>\n<table id=\"repeat-shots\">"
    << Row({"shot", "time offset (ms)", "clock vs the first shot (ms)", "knot-frames", "RMS (mm)",
            "max (mm)", "mean d²", "p", "verdict"},
           "th");
  for (size_t i = 0; i < repeats.shots.size(); ++i) {
    const ScoreSummary& s = repeats.shots[i].summary;
    o << Row({Escape(r.names[i]),
              Fixed(s.time_offset_s * 1e3, 3) + " ± " + Fixed(s.time_offset_sigma_s * 1e3, 3),
              i < r.spread_time_offset_s.size() ? Fixed(r.spread_time_offset_s[i] * 1e3, 3) : "",
              std::to_string(s.points), Fixed(s.rms_m * 1e3, 3), Fixed(s.max_m * 1e3, 2),
              Fixed(s.mean_d2, 2), Num(s.p_value, 3), VerdictName(s.verdict)});
  }
  o << Row({"<b>pooled</b>", "", "", std::to_string(r.points), Fixed(r.rms_m * 1e3, 3), "",
            Fixed(r.mean_d2, 2), Num(r.p_value, 3), "<b>" + VerdictName(r.verdict) + "</b>"});
  o << "</table>\n<p class=\"caption\">Pooled: mean d² over all " << r.points << " knot-frames, "
    << Fixed(r.effective_points, 0) << " independent points, the test rejects above "
    << Fixed(r.critical_mean_d2, 2) << ".</p>\n";
  o << "<h3>The spread between the repeats beside the model's error</h3>\n"
       "<table id=\"repeat-spread\">"
    << Row({"", "simulated time (s)", "knot-frames", "spread between shots (mm)",
            "model's RMS error (mm)"},
           "th");
  for (const SpreadRow& row : r.spread_per_phase)
    o << Row({"phase: " + row.name, Fixed(row.start_s, 3) + " – " + Fixed(row.end_s, 3),
              std::to_string(row.points), Fixed(row.rms_m * 1e3, 3),
              Fixed(row.error_rms_m * 1e3, 3)});
  for (const SpreadRow& row : r.spread_per_class)
    o << Row({row.name, "", std::to_string(row.points), Fixed(row.rms_m * 1e3, 3),
              Fixed(row.error_rms_m * 1e3, 3)});
  o << Row({"all", "", std::to_string(r.spread.points), Fixed(r.spread.rms_m * 1e3, 3),
            Fixed(r.spread.error_rms_m * 1e3, 3)});
  o << "</table>\n<p class=\"caption\">Spread: at the first shot's frames, every shot's "
       "measured knot at the same moment of the flight (the shots' clocks aligned to the first "
       "shot's where they lie closest to it: the column above; linear between a shot's two "
       "frames around that moment), in the simulation's frame; the RMS distance of one shot from "
       "the shots' mean, "
       "√(Σ|x − x̄|² / Σ(n − 1)). It is the experiment's reproducibility: a model error well "
       "below it cannot be told from one shot to the next. The plots and tables below are the "
       "first shot's ("
    << Escape(r.names[0]) << ").</p>\n";
}

}  // namespace

std::string ScoreReportHtml(const ScoreResult& r, const ReportInfo& info) {
  return ScoreReportHtml(r, info, nullptr);
}

std::string ScoreReportHtml(const ScoreResult& r, const ReportInfo& info,
                            const RepeatsResult* repeats) {
  std::ostringstream o;
  WriteHead(o, r.summary);
  WriteVerdict(o, r.summary, info);
  WriteNotes(o, r.summary);
  if (repeats) WriteRepeats(o, *repeats);
  WritePlots(o, r);
  WriteClassAndPhaseTables(o, r.summary);
  WriteAlignmentTable(o, r.summary);
  o << "</body></html>\n";
  return o.str();
}

void WriteScoreReport(const std::string& path, const ScoreResult& result, const ReportInfo& info) {
  WriteTextFile(path, ScoreReportHtml(result, info));
}

void WriteScoreReport(const std::string& path, const ScoreResult& result, const ReportInfo& info,
                      const RepeatsResult* repeats) {
  WriteTextFile(path, ScoreReportHtml(result, info, repeats));
}

}  // namespace netlab::netsim
