#pragma once
// The HTML report of `netlab sweep --report`: one self-contained file (inline CSS and SVG, no
// script, no link out), in the style of `netlab score`'s. It leads with the runs (how many, how
// many failed and why), then the sensitivities table (sweep_sensitivity.h), then per varied
// parameter a plot of each output against it (one line per combination of the other parameters'
// values, up to 6; beyond that the line through the other parameters' middle values), then every
// run in a table. docs/sweep.md explains how to read it.
//
// Every plotted line carries its data in SI units (as in sweep.h5's /runs/<output>) in
// data-values, and the runs it joins in data-runs:
//   <svg id="<output>-vs-<parameter index>">  <path data-series="..." data-runs=...
//   data-values=...> <table id="sensitivity">                  <td data-value=...> per output and
//   parameter

#include <string>
#include <vector>

#include "libnetsim/sweep/sweep_grid.h"
#include "libnetsim/sweep/sweep_runner.h"
#include "libnetsim/sweep/sweep_sensitivity.h"

namespace netlab::netsim {

struct SweepReportInfo {
  std::string scenario_path;  // shown in the header
  std::string sweep_path;     // the sweep.h5 written with it
  std::vector<ScenarioOverride> fixed;
};

std::string SweepReportHtml(const std::vector<SweepParameter>& parameters,
                            const std::vector<SweepPoint>& grid, const SweepResult& result,
                            const std::vector<std::vector<Sensitivity>>& sensitivity,
                            const SweepReportInfo& info);

// Writes it to `path` via "<path>.partial" and a rename. Throws std::runtime_error.
void WriteSweepReport(const std::string& path, const std::vector<SweepParameter>& parameters,
                      const std::vector<SweepPoint>& grid, const SweepResult& result,
                      const std::vector<std::vector<Sensitivity>>& sensitivity,
                      const SweepReportInfo& info);

}  // namespace netlab::netsim
