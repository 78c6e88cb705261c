#pragma once
// The HTML report of `netlab score`: one self-contained file (inline CSS and SVG, no script, no
// link out) that a person opens in a browser. It leads with the verdict and the few numbers that
// decide it, then the plots: error vs time per knot class, the per-knot error map over the grid,
// the corner-polygon area measured vs simulated, and the d2 histogram against chi^2_3; then the
// tables (per class, per phase, alignment). docs/score.md explains how to read it.
//
// Every plotted series carries its data as written to score.h5 (SI units, NaN as "nan") in a
// data-values attribute, so a test (and a curious reader) can check a plot against the file:
//   <svg id="error-vs-time">   <path data-series="corner|edge|inner" data-values=...>
//                              (/error_vs_time/rms_m)
//   <svg id="knot-map">        data-values (/knots/rms_m), one <rect data-knot="(r,c)"> per knot
//   <svg id="corner-area">     <path data-series="measured|simulated"> (/global/corner_area_*)
//   <svg id="d2-histogram">    <g data-series="counts"> bars, <path data-series="expected">
//                              (/d2_histogram/counts, expected)
// Time series also carry data-times (/time).

#include <string>

#include "libnetsim/validation/score.h"

namespace netlab::netsim {

struct ReportInfo {
  std::string measured_path;  // shown in the header
  std::string sim_path;
  std::string score_path;  // the score.h5 written next to it
};

struct RepeatsResult;

// The report as HTML text.
std::string ScoreReportHtml(const ScoreResult& result, const ReportInfo& info);
// With repeats (repeats.h; `result` is repeats->combined): a "Repeats" section after the notes,
// <table id="repeat-shots"> (one row per shot, then the pooled row) and <table
// id="repeat-spread"> (the spread between the shots beside the model's error, per phase, per
// knot class and over all).
std::string ScoreReportHtml(const ScoreResult& result, const ReportInfo& info,
                            const RepeatsResult* repeats);

// Writes it to `path` via "<path>.partial" and a rename. Throws std::runtime_error.
void WriteScoreReport(const std::string& path, const ScoreResult& result, const ReportInfo& info);
void WriteScoreReport(const std::string& path, const ScoreResult& result, const ReportInfo& info,
                      const RepeatsResult* repeats);

}  // namespace netlab::netsim
