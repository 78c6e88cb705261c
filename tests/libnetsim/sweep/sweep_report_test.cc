// The sweep's HTML report: its plots carry the runs' outputs (data-values, SI units), the
// sensitivities table carries ComputeSensitivities' numbers, failed runs are listed with why.

#include "libnetsim/sweep/sweep_report.h"

#include <gtest/gtest.h>

#include <regex>

namespace netlab::netsim {
namespace {

struct Fixture {
  std::vector<SweepParameter> parameters = {ParseVary("materials.pp.bend_stiffness=1e-4:3e-4:3"),
                                            ParseVary("drag.drag_coefficient=0.8:1.2:2")};
  std::vector<SweepPoint> grid = SweepGrid({}, parameters);
  SweepResult result;
  Fixture() {
    for (const SweepPoint& point : grid) {
      SweepRun run;
      run.index = point.index;
      run.outputs.max_area_m2 = 1e3 * point.values[0] + point.values[1];
      run.outputs.max_area_time_s = 0.1;
      run.outputs.max_penetration_m = 0.002;
      run.outputs.centroid_drift_m = point.values[1];
      result.runs.push_back(run);
    }
    result.runs[5].status = SweepRun::Status::kBlewUp;
    result.runs[5].error = "blew up at t = 0.01 s: node 3 <speed>";
    result.wall_s = 3.0;
  }
};

std::string Attribute(const std::string& html, const std::string& element_start,
                      const std::string& attribute) {
  const size_t at = html.find(element_start);
  if (at == std::string::npos) return "(no " + element_start + ")";
  const std::regex re(attribute + "=\"([^\"]*)\"");
  std::smatch m;
  const std::string rest = html.substr(at, html.find('>', at) - at);
  return std::regex_search(rest, m, re) ? m[1].str() : "(no " + attribute + ")";
}

TEST(SweepReport, PlotsCarryTheOutputsOfTheirRuns) {
  Fixture f;
  const auto sensitivity = ComputeSensitivities(f.parameters, f.result.runs);
  const std::string html =
      SweepReportHtml(f.parameters, f.grid, f.result, sensitivity, {"net.yaml", "sweep.h5", {}});
  // max_area against the first parameter: one line per value of the other (2 lines).
  const size_t plot = html.find("<svg id=\"max_area-vs-0\"");
  ASSERT_NE(plot, std::string::npos);
  const std::string rest = html.substr(plot);
  EXPECT_EQ(Attribute(rest, "<path data-series=\"drag.drag_coefficient = 0.8\"", "data-runs"),
            "0 2 4");
  EXPECT_EQ(Attribute(rest, "<path data-series=\"drag.drag_coefficient = 0.8\"", "data-values"),
            "0.9 1 1.1");  // 1e3 p + 0.8
  // Run 5 blew up: no value on its line, listed with its reason.
  EXPECT_EQ(Attribute(rest, "<path data-series=\"drag.drag_coefficient = 1.2\"", "data-values"),
            "1.3 1.4 nan");
  EXPECT_NE(html.find("run 5 (materials.pp.bend_stiffness = 0.0003, drag.drag_coefficient = "
                      "1.2), blew up: blew up at t = 0.01 s: node 3 &lt;speed&gt;"),
            std::string::npos);
  EXPECT_NE(html.find("5 of 6 runs finished"), std::string::npos);
  EXPECT_NE(html.find("<svg id=\"centroid_drift-vs-1\""), std::string::npos);
  // The same in every run: said, not plotted.
  EXPECT_EQ(html.find("<svg id=\"max_area_time-vs-0\""), std::string::npos);
  EXPECT_NE(html.find("0.1 s in every run."), std::string::npos);
  EXPECT_NE(html.find("2 mm in every run."), std::string::npos);
}

TEST(SweepReport, SensitivityTableHasTheComputedValues) {
  Fixture f;
  const auto sensitivity = ComputeSensitivities(f.parameters, f.result.runs);
  const std::string html =
      SweepReportHtml(f.parameters, f.grid, f.result, sensitivity, {"net.yaml", "sweep.h5", {}});
  const size_t table = html.find("<table id=\"sensitivity\">");
  ASSERT_NE(table, std::string::npos);
  // max_area = 1e3 p + d at the centre (p = 2e-4, d = 0.8): S_p = 1e3 p / o = 0.2; along d (two
  // values, p = 2e-4) S_d = (1.4 - 1.0) / 0.4 * 1.0 / 1.2 = 0.833 (bold: |S| >= 0.5); the
  // constant outputs 0.
  EXPECT_NEAR(sensitivity[0][0].value, 0.2, 1e-12);
  EXPECT_NEAR(sensitivity[0][1].value, 1.0 / 1.2, 1e-12);
  const std::string rest = html.substr(table);
  EXPECT_NE(rest.find("<td data-value=\"0.2\" title=\"runs 0 and 4\">0.200</td>"),
            std::string::npos);
  EXPECT_NE(rest.find("class=\"strong\" title=\"runs 2 and 3\">0.833</td>"), std::string::npos)
      << rest.substr(0, 2000);
  EXPECT_NE(rest.find(">0.000</td>"), std::string::npos);
}

}  // namespace
}  // namespace netlab::netsim
