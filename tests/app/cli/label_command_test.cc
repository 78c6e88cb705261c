// `netlab label` end to end on a rendered shot: seeds (the corners of the first frame, from the
// render's perfect labeling) in, labels.h5 out; the JSON contract; no accepted label on another
// knot's place; bad input.

#include <gtest/gtest.h>

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

class LabelCommand : public netlab::testing::CommandTest {
 protected:
  LabelCommand() : CommandTest("label_cli") {}
  void SetUp() override {
    CommandTest::SetUp();
    std::ofstream(Path("scenario.yaml")) << netlab::testing::kSmallShotScenario;
    ASSERT_EQ(
        RunNetlab("simulate " + Path("scenario.yaml") + " --out " + Path("sim.h5") + " --quiet")
            .status,
        0);
    ASSERT_EQ(RunNetlab("color-net --knots 6x6 --out " + Path("coloring.yaml") + " --quiet").status,
              0);
    const auto render = RunNetlab("render --sim " + Path("sim.h5") + " --out " + Path("shot") +
                                  " --frames 0:4 --calibration-views 0 --coloring " +
                                  Path("coloring.yaml") + " --quiet");
    ASSERT_EQ(render.status, 0) << render.err;
    truth_ = recon::ReadLabels(Path("shot/labels_true.h5"));
    // Seeds: the four corners of the first frame, wherever a camera sees them.
    recon::LabelSet seeds =
        recon::LabelSet::Empty(6, 6, truth_.cameras, {truth_.frame_index.front()});
    for (int c = 0; c < static_cast<int>(truth_.cameras.size()); ++c)
      for (int k : {0, 5, 30, 35}) seeds.at(c, 0, k) = truth_.at(c, 0, k);
    recon::WriteLabels(Path("seeds.h5"), seeds);
  }
  std::string Base() const {
    return "label " + Path("shot/experiment.yaml") + " --rig " + Path("shot/rig_true.yaml") +
           " --coloring " + Path("coloring.yaml") + " ";
  }
  recon::LabelSet truth_;
};

TEST_F(LabelCommand, LabelsFromSeedsAndNeverAcceptsAWrongLabel) {
  const auto r = RunNetlab(Base() + "--seed " + Path("seeds.h5") + " --out " + Path("labels.h5") +
                           " --xypts " + Path("xypts.csv") + " --json");
  ASSERT_EQ(r.status, 0) << r.err;
  const Json json = LastJson(r.out);
  for (const char* key : {"labeled", "needs_review", "frames", "wall_s"})
    EXPECT_TRUE(json.has(key)) << key;
  EXPECT_EQ(json["frames"].number(), 5);
  const recon::LabelSet labels = recon::ReadLabels(Path("labels.h5"));
  int64_t present = 0, review = 0, accepted = 0;
  for (int c = 0; c < static_cast<int>(labels.cameras.size()); ++c)
    for (int t = 0; t < labels.frames(); ++t)
      for (int k = 0; k < labels.knots(); ++k) {
        const recon::Label& l = labels.at(c, t, k);
        if (!l.present()) continue;
        ++present;
        review += l.state == recon::LabelState::kNeedsReview;
        if (l.state != recon::LabelState::kAccepted) continue;
        ++accepted;
        const recon::Label& truth = truth_.at(c, t, k);
        ASSERT_TRUE(truth.present()) << "accepted a label for a hidden knot";
        EXPECT_LT((l.px - truth.px).norm(), 2.0)
            << "camera " << c << " frame " << t << " knot " << k;
      }
  EXPECT_EQ(json["labeled"].number(), present);
  EXPECT_EQ(json["needs_review"].number(), review);
  EXPECT_GE(accepted, 4);  // at least the seeds
  // The DLTdv8 export holds the same labels.
  const recon::LabelSet xy = recon::ReadXyPts(Path("xypts.csv"), 6, 6, labels.cameras);
  EXPECT_EQ(xy.CountPresent(), present);
}

TEST_F(LabelCommand, BadInputIsNamed) {
  auto r = RunNetlab(Base() + "--seed " + Path("missing.h5") + " --out " + Path("l.h5"));
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("missing.h5"), std::string::npos) << r.err;
  r = RunNetlab(Base() + "--seed " + Path("seeds.h5") + " --out " + Path("l.h5") +
                " --frames 3:99");
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("--frames"), std::string::npos) << r.err;
  std::ofstream(Path("other.csv")) << "pt1_cam9_X,pt1_cam9_Y\n1,2\n";
  r = RunNetlab(Base() + "--seed " + Path("other.csv") + " --out " + Path("l.h5"));
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("cam9"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(Path("l.h5")));
}

}  // namespace
