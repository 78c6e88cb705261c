// The whole loop as a user runs it, on a short rendered shot: simulate → render → label from the
// corners each camera sees in the first frame (the truth standing for a person's clicks) →
// triangulate → score → fit. Against the simulation that made the shot the verdict is
// "consistent"; against one launched 10 % faster it is "inconsistent". No accepted label is
// another knot's. Fitted from half its speed, the launch comes back within its sigma.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <string>

#include "libreconstruct/labels/label_set.h"
#include "tests/app/cli/run_netlab.h"
#include "tests/app/cli/small_shot.h"

namespace {

using netlab::testing::Json;
using netlab::testing::LastJson;
using netlab::testing::RunNetlab;
namespace recon = netlab::recon;

constexpr int kLastFrame = 15;

// The small shot, long enough for 16 frames, launched at `speed` m/s.
std::string Scenario(const std::string& speed) {
  std::string s = netlab::testing::kSmallShotScenario;
  auto replace = [&s](const std::string& from, const std::string& to) {
    const size_t at = s.find(from);
    ASSERT_NE(at, std::string::npos) << from;
    s.replace(at, from.size(), to);
  };
  replace("duration: 0.06", "duration: 0.1");
  replace("velocity: [0.5, 0, 0]", "velocity: [" + speed + ", 0, 0]");
  return s;
}

class FullLoop : public netlab::testing::CommandTest {
 protected:
  FullLoop() : CommandTest("full_loop") {}

  void Run(const std::string& args) {
    const auto r = RunNetlab(args + " --quiet");
    ASSERT_EQ(r.status, 0) << args << "\n" << r.err;
  }
  // Seeds: the corners of the first frame that each camera sees (hidden or outside: none).
  void WriteSeeds() {
    const recon::LabelSet truth = recon::ReadLabels(Path("shot/labels_true.h5"));
    recon::LabelSet seeds =
        recon::LabelSet::Empty(6, 6, truth.cameras, {truth.frame_index.front()});
    for (int c = 0; c < static_cast<int>(truth.cameras.size()); ++c)
      for (int k : {0, 5, 30, 35})
        if (truth.at(c, 0, k).present()) seeds.at(c, 0, k) = truth.at(c, 0, k);
    recon::WriteLabels(Path("seeds.h5"), seeds);
  }
  // Accepted labels, and those on no knot's true place (2 px).
  void CountLabels(int* accepted, int* wrong) const {
    const recon::LabelSet truth = recon::ReadLabels(Path("shot/labels_true.h5"));
    const recon::LabelSet labels = recon::ReadLabels(Path("labels.h5"));
    *accepted = *wrong = 0;
    for (int c = 0; c < static_cast<int>(labels.cameras.size()); ++c)
      for (int t = 0; t < labels.frames(); ++t)
        for (int k = 0; k < labels.knots(); ++k) {
          const recon::Label& l = labels.at(c, t, k);
          if (!l.accepted()) continue;
          ++*accepted;
          const recon::Label& want = truth.at(truth.FindCamera(labels.cameras[c]), t, k);
          *wrong += !want.present() || (l.px - want.px).norm() > 2.0;
        }
  }
  Json Score(const std::string& sim) {
    const auto r = RunNetlab("score --measured " + Path("tracks.h5") + " --sim " + Path(sim) +
                             " --out " + Path(sim + ".score.h5") + " --align time --json");
    EXPECT_EQ(r.status, 0) << r.err;
    return LastJson(r.out);
  }
};

TEST_F(FullLoop, LabelsFromTheCornersScoreConsistentWithTheirSimulationOnly) {
  std::ofstream(Path("shot.yaml")) << Scenario("0.5");
  std::ofstream(Path("fast.yaml")) << Scenario("0.55");
  Run("simulate " + Path("shot.yaml") + " --out " + Path("sim.h5"));
  Run("simulate " + Path("fast.yaml") + " --out " + Path("fast.h5"));
  Run("color-net --knots 6x6 --out " + Path("coloring.yaml"));
  Run("render --sim " + Path("sim.h5") + " --out " + Path("shot") + " --frames 0:" +
      std::to_string(kLastFrame) + " --calibration-views 0 --coloring " + Path("coloring.yaml"));
  WriteSeeds();
  Run("label " + Path("shot/experiment.yaml") + " --rig " + Path("shot/rig_true.yaml") +
      " --coloring " + Path("coloring.yaml") + " --seed " + Path("seeds.h5") + " --out " +
      Path("labels.h5"));
  int accepted = 0, wrong = 0;
  CountLabels(&accepted, &wrong);
  EXPECT_EQ(wrong, 0);
  // Most of the 36 knots in two cameras or more, every frame: 2 x 36 x 16 = 1152.
  EXPECT_GT(accepted, 1152);
  // The labels' accuracy on the twin as their stated uncertainty (scripts/demo.sh).
  Run("triangulate --rig " + Path("shot/rig_true.yaml") + " --labels " + Path("labels.h5") +
      " --knots 6x6 --fps 179 --sigma-px 0.09 --out " + Path("tracks.h5"));

  const Json right = Score("sim.h5");
  EXPECT_EQ(right["verdict"].string(), "consistent");
  EXPECT_GT(right["points"].number(), 0.8 * 36 * (kLastFrame + 1));
  EXPECT_LT(right["rms_mm"].number(), 0.5);
  EXPECT_NEAR(right["time_offset_s"].number(), 0.0, 1e-3);
  const Json fast = Score("fast.h5");
  EXPECT_EQ(fast["verdict"].string(), "inconsistent");
  EXPECT_GT(fast["rms_mm"].number(), 3 * right["rms_mm"].number());
  std::printf("%d labels accepted; right: %g points, %g mm RMS, mean d2 %g; fast: %g mm, %g\n",
              accepted, right["points"].number(), right["rms_mm"].number(),
              right["mean_d2"].number(), fast["rms_mm"].number(), fast["mean_d2"].number());

  // The loop closed: the launch identified from the triangulated tracks (their own covariance),
  // from half the true speed; within 3 of its sigmas, and the sigma small.
  const auto fit = RunNetlab("fit " + Path("shot.yaml") + " --measured " + Path("tracks.h5") +
                             " --free nets.0.velocity,time_offset --set nets.0.velocity=[0.25,0,0]"
                             " --out " +
                             Path("fit.yaml") + " --json --quiet");
  ASSERT_EQ(fit.status, 0) << fit.err;
  const Json fitted = LastJson(fit.out);
  const Json& vx = fitted["parameters"]["nets.0.velocity.0"];
  EXPECT_TRUE(vx["identified"].boolean());
  EXPECT_LT(std::abs(vx["value"].number() - 0.5), 3 * vx["sigma"].number())
      << vx["value"].number() << " +- " << vx["sigma"].number();
  EXPECT_LT(vx["sigma"].number(), 0.005);
  EXPECT_LT(std::abs(fitted["parameters"]["time_offset"]["value"].number()),
            3 * fitted["parameters"]["time_offset"]["sigma"].number());
  std::printf("fit from the triangulated tracks: vx %g +- %g m/s, %g simulations\n",
              vx["value"].number(), vx["sigma"].number(), fitted["simulations"].number());
}

}  // namespace
