// Sensitivities d ln(output)/d ln(parameter) against closed forms: a power law o = c p^k has
// S = k, which the central difference at the grid's centre gives exactly for k = 1 and 2.

#include "libnetsim/sweep/sweep_sensitivity.h"

#include <gtest/gtest.h>

#include <cmath>

namespace netlab::netsim {
namespace {

// Runs of the grid of `parameters` whose max_area is f(values) (the other outputs 1).
template <typename F>
std::vector<SweepRun> FakeRuns(const std::vector<SweepParameter>& parameters, F f) {
  std::vector<SweepRun> runs;
  for (const SweepPoint& point : SweepGrid({}, parameters)) {
    SweepRun run;
    run.index = point.index;
    run.outputs.max_area_m2 = f(point.values);
    run.outputs.max_area_time_s = run.outputs.centroid_drift_m = 1.0;
    run.outputs.max_penetration_m = 0.0;
    runs.push_back(run);
  }
  return runs;
}

TEST(Sensitivity, PowerLawsGiveTheirExponent) {
  // o = 3 p^2 q: S_p = 2 (odd count: centre p = 2), S_q = 1 (even count: the middle pair).
  const std::vector<SweepParameter> parameters = {ParseVary("a.p=1:3:3"), ParseVary("a.q=1:4:4")};
  const auto runs =
      FakeRuns(parameters, [](const std::vector<double>& v) { return 3 * v[0] * v[0] * v[1]; });
  const auto table = ComputeSensitivities(parameters, runs);
  ASSERT_EQ(table.size(), kSweepOutputs.size());
  EXPECT_DOUBLE_EQ(table[0][0].value, 2.0);
  EXPECT_DOUBLE_EQ(table[0][1].value, 1.0);
  // The runs used: p at 1 and 3 with q at its lower middle value (index 1).
  EXPECT_EQ(table[0][0].run_low, GridIndex(parameters, {0, 1}));
  EXPECT_EQ(table[0][0].run_high, GridIndex(parameters, {2, 1}));
  EXPECT_EQ(table[0][1].run_low, GridIndex(parameters, {1, 1}));
  EXPECT_EQ(table[0][1].run_high, GridIndex(parameters, {1, 2}));
  EXPECT_EQ(table[1][0].value, 0.0);           // a constant output
  EXPECT_TRUE(std::isnan(table[2][0].value));  // 0 at the centre: no log
  EXPECT_EQ(table[2][0].why_not, "0 at the centre");
}

TEST(Sensitivity, UndefinedWithOneValueOrAFailedRun) {
  const std::vector<SweepParameter> parameters = {ParseVary("a.p=1:3:3"), ParseVary("a.q=5:5:1")};
  auto runs = FakeRuns(parameters, [](const std::vector<double>& v) { return v[0]; });
  runs[2].status = SweepRun::Status::kBlewUp;
  const auto table = ComputeSensitivities(parameters, runs);
  EXPECT_TRUE(std::isnan(table[0][0].value));
  EXPECT_EQ(table[0][0].why_not, "a run failed");
  EXPECT_TRUE(std::isnan(table[0][1].value));
  EXPECT_EQ(table[0][1].why_not, "one value");
}

}  // namespace
}  // namespace netlab::netsim
