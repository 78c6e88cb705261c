// The run pool of `netlab sweep`: the same bits as a single run whatever the threads, failed runs
// kept in the result, the outputs against known answers, the callbacks on the calling thread.

#include "libnetsim/sweep/sweep_runner.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <thread>

#include "common/tracks/track_file.h"
#include "libnetsim/scenario/run_scenario.h"

namespace netlab::netsim {
namespace {

// 3 x 4 knots, 10 cm mesh, no gravity: at rest unless given a velocity. 0.02 s, 5 frames.
constexpr char kNet[] = R"(name: small_net
duration: 0.02
output_interval: 0.005
integrator: {type: explicit, dt: 2.0e-5}
materials:
  pp: {diameter: 1.0e-3, linear_density: 7.1e-4, stretch_stiffness: 1178,
       bend_stiffness: 7.36e-5, twist_stiffness: 5.45e-5}
nets:
  - {name: net, material: pp, knots: [3, 4], mesh: 0.1, segments_per_link: 2, center: [0, 0, 0.2],
     corner_mass: 0.01, velocity: [0, 0, 0]}
)";

class Sweep : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() /
           ("sweep_runner_test_" + std::to_string(getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    std::filesystem::create_directories(dir_);
    scenario_ = (dir_ / "net.yaml").string();
    std::ofstream(scenario_) << kNet;
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  std::filesystem::path dir_;
  std::string scenario_;
};

std::vector<std::vector<ScenarioOverride>> VelocitySets() {
  std::vector<std::vector<ScenarioOverride>> sets;
  for (const char* v : {"[0, 0, 0]", "[0.1, 0, 0]", "[0, 0.2, 0]", "[0.3, 0, 0.1]"})
    sets.push_back({{"nets.0.velocity", v}, {"materials.pp.bend_stiffness", "1e-4"}});
  return sets;
}

// Each run is `netlab simulate --set ...` of its set: the knot tracks bit for bit, with one
// thread or two.
TEST_F(Sweep, RunsAreBitIdenticalToSingleRunsWithAnyThreads) {
  const auto sets = VelocitySets();
  SweepOptions options;
  options.jobs = 1;
  const SweepResult one = RunSweep(scenario_, sets, options);
  options.jobs = 2;
  const SweepResult two = RunSweep(scenario_, sets, options);
  ASSERT_EQ(one.runs.size(), sets.size());
  ASSERT_EQ(two.runs.size(), sets.size());
  EXPECT_EQ(two.jobs, 2);
  for (size_t i = 0; i < sets.size(); ++i) {
    RunOptions single;
    single.out_path = (dir_ / ("single" + std::to_string(i) + ".h5")).string();
    ASSERT_TRUE(RunScenario(LoadScenario(scenario_, sets[i]), single).stable);
    const KnotTracks tracks = ReadKnotTracks(single.out_path);
    for (const SweepResult* r : {&one, &two}) {
      const SweepRun& run = r->runs[i];
      EXPECT_TRUE(run.ok()) << run.error;
      EXPECT_EQ(run.index, static_cast<int>(i));
      EXPECT_EQ(run.time, tracks.time);
      ASSERT_EQ(run.knots.size(), tracks.position.size());
      for (size_t k = 0; k < run.knots.size(); ++k)
        ASSERT_TRUE(run.knots[k] == tracks.position[k]) << "run " << i << " knot-frame " << k;
      EXPECT_EQ(run.grid, tracks.grid);
    }
  }
}

// The outputs against what a net flying at constant speed with no force does: it keeps its
// shape (the area is the mesh's, from the first frame) and its centroid moves v t.
TEST_F(Sweep, OutputsOfAFreeFlightAreKnown) {
  const SweepRun run = RunOne(scenario_, 0, {{"nets.0.velocity", "[0.1, 0, 0.2]"}}, 1);
  ASSERT_TRUE(run.ok()) << run.error;
  EXPECT_NEAR(run.outputs.max_area_m2, 0.2 * 0.3, 1e-9);  // (3-1) x (4-1) meshes of 0.1 m
  EXPECT_NEAR(run.outputs.centroid_drift_m, std::hypot(0.1, 0.2) * 0.02, 1e-9);
  EXPECT_EQ(run.outputs.max_penetration_m, 0.0);
  EXPECT_EQ(run.summary.frames, 5);
  EXPECT_EQ(run.time.size(), 5u);
  EXPECT_EQ(run.knots.size(), 5u * 12);
}

TEST_F(Sweep, DecimateKeepsEveryNthFrameButOutputsSeeAll) {
  const SweepRun all = RunOne(scenario_, 0, {{"nets.0.velocity", "[0.1, 0, 0]"}}, 1);
  const SweepRun some = RunOne(scenario_, 0, {{"nets.0.velocity", "[0.1, 0, 0]"}}, 2);
  ASSERT_EQ(some.time.size(), 3u);  // frames 0, 2, 4
  EXPECT_EQ(some.time[1], all.time[2]);
  EXPECT_TRUE(some.knots[12 * 2 + 5] == all.knots[12 * 4 + 5]);
  EXPECT_EQ(some.outputs.centroid_drift_m, all.outputs.centroid_drift_m);
}

// A run that blows up and one whose value the scenario rejects are part of the result, with why;
// the others run to the end.
TEST_F(Sweep, FailedRunsAreReportedAndTheOthersKept) {
  std::vector<std::vector<ScenarioOverride>> sets = {
      {{"materials.pp.bend_stiffness", "1e-4"}},
      // Absurdly stiff at the fixed dt, and bent (folded links): blows up.
      {{"materials.pp.bend_stiffness", "1e4"}, {"nets.0.spread", "0.6"}},
      {{"materials.pp.bend_stiffness", "-1"}},  // rejected by the scenario's check
      {{"materials.pp.bend_stiffness", "2e-4"}}};
  SweepOptions options;
  options.jobs = 2;
  const SweepResult result = RunSweep(scenario_, sets, options);
  ASSERT_EQ(result.runs.size(), 4u);
  EXPECT_EQ(result.failed(), 2);
  EXPECT_TRUE(result.runs[0].ok());
  EXPECT_TRUE(result.runs[3].ok());
  EXPECT_EQ(result.runs[1].status, SweepRun::Status::kBlewUp);
  EXPECT_NE(result.runs[1].error.find("blew up at t = "), std::string::npos)
      << result.runs[1].error;
  EXPECT_FALSE(result.runs[1].time.empty());  // the frames up to the blow-up
  EXPECT_EQ(result.runs[2].status, SweepRun::Status::kBadValue);
  EXPECT_NE(result.runs[2].error.find("bend_stiffness: must be > 0"), std::string::npos)
      << result.runs[2].error;
  EXPECT_NE(result.runs[2].error.find("--set materials.pp.bend_stiffness=-1"), std::string::npos);
  EXPECT_EQ(result.runs[3].summary.frames, 5);
}

TEST_F(Sweep, CallbacksComeOnTheCallingThreadOncePerRun) {
  const auto sets = VelocitySets();
  const auto caller = std::this_thread::get_id();
  std::vector<int> seen, done;
  SweepOptions options;
  options.jobs = 2;
  options.keep_tracks = false;
  options.on_run = [&](const SweepRun& run, int d, int total) {
    EXPECT_EQ(std::this_thread::get_id(), caller);
    EXPECT_EQ(total, 4);
    EXPECT_FALSE(run.time.empty());  // the callback sees the tracks
    seen.push_back(run.index);
    done.push_back(d);
  };
  const SweepResult result = RunSweep(scenario_, sets, options);
  std::sort(seen.begin(), seen.end());
  EXPECT_EQ(seen, (std::vector<int>{0, 1, 2, 3}));
  EXPECT_EQ(done, (std::vector<int>{1, 2, 3, 4}));
  for (const SweepRun& run : result.runs) EXPECT_TRUE(run.time.empty());  // not kept
  EXPECT_GT(result.wall_s, 0.0);
  EXPECT_EQ(result.ranks, 1);
}

}  // namespace
}  // namespace netlab::netsim
