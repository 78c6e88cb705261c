// The recording room without a window (app/gui/document/recording_presenter.h): on three cameras
// of six frames, one missing a frame and one whose clock runs 0.6 ms ahead and sends one time
// twice, the findings table, the timeline's marks and the timestamp offsets say exactly that.

#include "app/gui/document/recording_presenter.h"

#include <gtest/gtest.h>

#include <QCoreApplication>
#include <string>
#include <vector>

#include "common/errors.h"
#include "tests/libreconstruct/test_files.h"

namespace netlab::gui {
namespace {

using recon::testing::ScratchDir;
using recon::testing::WriteBytes;
using recon::testing::WritePgm;

constexpr int kFrames = 6;
constexpr double kFps = 100.0;

class ThreeCameras : public ::testing::Test {
 protected:
  ThreeCameras() : dir_("recording_presenter") {
    std::string yaml = "experiment: three\nfps: 100\ncameras:\n";
    for (int c = 0; c < 3; ++c) {
      const std::string name = "cam" + std::to_string(c);
      std::string times = "frame_index,time_s\n";
      for (int k = 0; k < kFrames; ++k) {
        if (c == 1 && k == 3) continue;  // cam1: frame 3 missing
        char file[64];
        std::snprintf(file, sizeof file, "%s/frame_%04d.pgm", name.c_str(), k);
        WritePgm(dir_ / file, cv::Mat(16, 16, CV_8UC1, cv::Scalar(40 + 10 * k)));
        // cam2: 0.6 ms ahead, and frame 4 sent with frame 3's time.
        const double t = (c == 2 && k == 4 ? 3 : k) / kFps + (c == 2 ? 0.6e-3 : 0.0);
        times += std::to_string(k) + "," + std::to_string(t) + "\n";
      }
      WriteBytes(dir_ / (name + "/times.csv"), times);
      yaml += "  - name: " + name + "\n    frames: " + name +
              "/frame_%04d.pgm\n    bayer: RGGB\n    timestamps: " + name + "/times.csv\n";
    }
    WriteBytes(dir_ / "experiment.yaml", yaml);
  }
  ScratchDir dir_;
};

TEST_F(ThreeCameras, FindingsAndMarksNameTheCameraTheKindAndTheFrames) {
  RecordingPresenter recording(dir_ / "experiment.yaml");
  EXPECT_TRUE(recording.Findings().empty()) << "no report yet";
  EXPECT_TRUE(recording.Summary().contains("checking"));
  recording.SetReport(RecordingPresenter::Check(recording.sequence(), false));
  const std::vector<RecordingFinding> rows = recording.Findings();
  bool missing = false, duplicated = false;
  for (const RecordingFinding& f : rows) {
    if (f.camera_name == "cam1" && f.kind == "missing") {
      missing = true;
      EXPECT_EQ(f.frames, std::vector<int>{3});
    }
    if (f.camera_name == "cam2" && f.kind == "duplicated") {
      duplicated = true;
      EXPECT_EQ(f.frames, std::vector<int>{4});
    }
    EXPECT_NE(f.camera_name, "cam0") << "cam0 is whole: " << f.kind;
  }
  EXPECT_TRUE(missing);
  EXPECT_TRUE(duplicated);
  EXPECT_TRUE(recording.MarkedFrames().count(3));
  EXPECT_TRUE(recording.MarkedFrames().count(4));
  EXPECT_FALSE(recording.MarkedFrames().count(0));
  EXPECT_TRUE(recording.Summary().contains("3 cameras, frames 0–5 at 100 fps"));
}

TEST_F(ThreeCameras, OffsetsAreEachCamerasTimeMinusTheCamerasMean) {
  const RecordingPresenter recording(dir_ / "experiment.yaml");
  const std::vector<TimestampSeries> series = recording.Offsets();
  ASSERT_EQ(series.size(), 3u);
  EXPECT_EQ(series[2].camera, "cam2");
  // Frame 3 has no time in cam1: left out of every series.
  ASSERT_EQ(series[0].points.size(), static_cast<size_t>(kFrames - 1));
  for (const Eigen::Vector2d& p : series[0].points) EXPECT_NE(p.x(), 3.0);
  // Frame 0: cam2 0.6 ms ahead of the two others, so 0.4 ms above their mean, they 0.2 below.
  EXPECT_NEAR(series[2].points[0].y(), 0.4, 1e-3);
  EXPECT_NEAR(series[0].points[0].y(), -0.2, 1e-3);
  EXPECT_NEAR(series[1].points[0].y(), -0.2, 1e-3);
}

TEST(RecordingPresenter, FrameListShowsAFewNumbersAndTheCount) {
  EXPECT_EQ(RecordingPresenter::FrameList({7}), "7 (1 frame)");
  EXPECT_EQ(RecordingPresenter::FrameList({1, 2, 3, 4}, 2), "1, 2 … (4 frames)");
}

TEST(RecordingPresenter, AnExperimentThatCannotBeReadIsAnInputErrorNamingIt) {
  try {
    RecordingPresenter recording("/nonexistent/experiment.yaml");
    FAIL() << "opened a file that does not exist";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/experiment.yaml"), std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace netlab::gui
