#include "libreconstruct/recording/sequence.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "common/errors.h"
#include "tests/libreconstruct/test_files.h"

namespace netlab::recon {
namespace {

using testing::PgmBytes;
using testing::SameImage;
using testing::ScratchDir;
using testing::WriteBytes;
using testing::WritePgm;

constexpr int kWidth = 64, kHeight = 48, kFrames = 10;
constexpr double kFps = 100.0;

// The flat grey level of frame k of camera c: a mosaic of one value demosaics to that grey, so
// the frame (and camera) any image came from can be read back from any pixel at any level.
uint8_t Level(int camera, int k) { return static_cast<uint8_t>(20 + 20 * k + camera); }

cv::Mat Frame(int camera, int k, cv::Size size = {kWidth, kHeight}) {
  return cv::Mat(size, CV_8UC1, cv::Scalar(Level(camera, k)));
}

std::string FrameName(int k) {
  char buffer[32];
  std::snprintf(buffer, sizeof(buffer), "frame_%04d.pgm", k);
  return buffer;
}

// Four cameras, frames 0..9, RGGB mosaics, 100 fps:
//   cam0  complete; its timestamps skip one period after frame 6 (a frame dropped by the camera)
//   cam1  lacks frame 5 (an index gap)
//   cam2  frame 4 is a copy of frame 3 (identical pixels); frame 7 has the timestamp of frame 6
//         (the camera sent one frame twice; later frames keep the period)
//   cam3  frame 2 is garbage, frame 8 is cut short
class FourCameras : public ::testing::Test {
 protected:
  FourCameras() : dir_("sequence") {
    for (int c = 0; c < 4; ++c)
      for (int k = 0; k < kFrames; ++k) {
        const std::string path = File(c, k);
        if (c == 1 && k == 5) continue;
        if (c == 2 && k == 4) {
          WritePgm(path, Frame(2, 3));
        } else if (c == 3 && k == 2) {
          const char garbage[] = "\x89garbage bytes, not a PGM\0\x01\x02";
          WriteBytes(path, std::string(garbage, sizeof(garbage) - 1));
        } else if (c == 3 && k == 8) {
          WriteBytes(path, PgmBytes(Frame(c, k)).substr(0, 1000));
        } else {
          WritePgm(path, Frame(c, k));
        }
      }
    std::string cam0 = "frame_index,time_s\n", cam2 = cam0;
    for (int k = 0; k < kFrames; ++k) {
      cam0 += std::to_string(k) + "," + std::to_string((k + (k >= 7 ? 1 : 0)) / kFps) + "\n";
      cam2 += std::to_string(k) + "," + std::to_string((k - (k >= 7 ? 1 : 0)) / kFps) + "\n";
    }
    WriteBytes(dir_ / "cam0_times.csv", cam0);
    WriteBytes(dir_ / "cam2_times.csv", cam2);
  }

  std::string File(int camera, int k) const {
    return dir_ / ("cam" + std::to_string(camera) + "/" + FrameName(k));
  }

  Experiment MakeExperiment() const {
    Experiment e;
    e.name = "four";
    e.fps = kFps;
    e.path = dir_ / "experiment.yaml";
    e.base_dir = dir_.path().string();
    for (int c = 0; c < 4; ++c) {
      CameraSpec spec;
      spec.name = "cam" + std::to_string(c);
      spec.frames = spec.name + "/frame_%04d.pgm";
      spec.bayer = BayerPattern::kRGGB;
      if (c == 0 || c == 2) spec.timestamps = dir_ / (spec.name + "_times.csv");
      e.cameras.push_back(spec);
    }
    return e;
  }

  ScratchDir dir_;
};

// The problem line of `camera` that mentions frame `k`, or "".
std::string ProblemOf(const CameraReport& camera, int k) {
  for (const std::string& p : camera.problems)
    if (p.find(" frame " + std::to_string(k) + " ") != std::string::npos) return p;
  return "";
}

void ExpectFourCameraReport(const CheckReport& r, bool decoded, const std::string& dir) {
  using V = std::vector<int>;
  EXPECT_EQ(r.first_frame, 0);
  EXPECT_EQ(r.last_frame, kFrames - 1);
  EXPECT_EQ(r.decoded, decoded);
  ASSERT_EQ(r.cameras.size(), 4u);
  for (int c = 0; c < 4; ++c) {
    SCOPED_TRACE("cam" + std::to_string(c));
    const CameraReport& cam = r.cameras[c];
    EXPECT_EQ(cam.name, "cam" + std::to_string(c));
    EXPECT_EQ(cam.frames, c == 1 ? kFrames - 1 : kFrames);
    EXPECT_EQ(cam.width, kWidth);
    EXPECT_EQ(cam.height, kHeight);
    EXPECT_EQ(cam.depth_bits, 8);
    EXPECT_EQ(cam.missing, c == 1 ? V{5} : V{});
    EXPECT_EQ(cam.unreadable, c == 3 ? (V{2, 8}) : V{});
    EXPECT_EQ(cam.timestamp_gaps, c == 0 ? V{6} : V{});
    // Identical pixels are only seen when decoding; the repeated timestamp always.
    EXPECT_EQ(cam.duplicated, c == 2 ? (decoded ? V{4, 7} : V{7}) : V{});
    EXPECT_EQ(cam.problems.size(), c == 3 ? 2u : 0u);
  }
  const CameraReport& cam3 = r.cameras[3];
  const std::string garbage = ProblemOf(cam3, 2), cut = ProblemOf(cam3, 8);
  EXPECT_NE(garbage.find("cam3 frame 2 (" + dir + "/cam3/frame_0002.pgm)"), std::string::npos)
      << garbage;
  EXPECT_GT(garbage.size(), garbage.find("): ") + 4) << "no reason given: " << garbage;
  EXPECT_NE(cut.find("cam3 frame 8 (" + dir + "/cam3/frame_0008.pgm)"), std::string::npos) << cut;
  EXPECT_NE(cut.find("truncated"), std::string::npos) << cut;
  // Every camera readable: all but 5 (cam1) and 2, 8 (cam3).
  EXPECT_EQ(r.synchronized_frames, 7);
  EXPECT_EQ(r.frames_read, 4 * kFrames - 1);
  // Different frame counts (cam1 has 9) are worth a warning; sizes agree.
  ASSERT_EQ(r.warnings.size(), 1u);
  EXPECT_NE(r.warnings[0].find("cam0 and cam1 differ in frame count (10 and 9)"), std::string::npos)
      << r.warnings[0];
}

TEST_F(FourCameras, HeaderCheckReportsGapsUnreadableFilesAndTimestamps) {
  const SynchronizedSequence sequence(MakeExperiment());
  EXPECT_EQ(sequence.num_cameras(), 4);
  EXPECT_EQ(sequence.first_frame(), 0);
  EXPECT_EQ(sequence.last_frame(), kFrames - 1);
  int calls = 0, last = 0;
  const CheckReport report = sequence.Check(false, ProgressReporter([&](const Progress& p) {
                                              ++calls;
                                              last = static_cast<int>(p.done);
                                              EXPECT_EQ(p.total, 4 * kFrames - 1);
                                              EXPECT_EQ(p.stage, "frame headers read");
                                            }));
  EXPECT_EQ(calls, 4 * kFrames - 1);
  EXPECT_EQ(last, 4 * kFrames - 1);
  ExpectFourCameraReport(report, false, dir_.path().string());
  const std::string brief = report.BriefReport();
  EXPECT_NE(brief.find("7 synchronized"), std::string::npos) << brief;
  EXPECT_NE(brief.find("cam1: 9 frames 64x48 (8 bit); missing 5"), std::string::npos) << brief;
  EXPECT_NE(brief.find("unreadable 2, 8"), std::string::npos) << brief;
  EXPECT_NE(brief.find("timestamps skip after 6"), std::string::npos) << brief;
}

TEST_F(FourCameras, DecodingCheckAlsoFindsIdenticalFramesOnOneOrTwoThreads) {
  const SynchronizedSequence sequence(MakeExperiment());
  for (int threads : {1, 2, 3}) {
    SCOPED_TRACE(std::to_string(threads) + " threads");
    const CheckReport report = sequence.Check(true, {}, threads);
    ExpectFourCameraReport(report, true, dir_.path().string());
  }
}

TEST_F(FourCameras, FramesAfterAGapAreNotShifted) {
  const SynchronizedSequence sequence(MakeExperiment());
  std::string error;
  for (int c = 0; c < 4; ++c)
    for (int k = 0; k < kFrames; ++k) {
      SCOPED_TRACE("cam" + std::to_string(c) + " frame " + std::to_string(k));
      error.clear();
      const cv::Mat raw = sequence.ReadRaw(c, k, &error);
      if ((c == 1 && k == 5) || (c == 3 && (k == 2 || k == 8))) {
        EXPECT_TRUE(raw.empty());
        EXPECT_FALSE(error.empty());
        continue;
      }
      const int expected = c == 2 && k == 4 ? 3 : k;  // the copied frame
      EXPECT_TRUE(SameImage(raw, Frame(c, expected))) << error;
    }
  EXPECT_FALSE(sequence.Has(1, 5));
  EXPECT_TRUE(sequence.Has(1, 6));
  EXPECT_TRUE(sequence.Has(3, 8));  // present, if unreadable
  error.clear();
  EXPECT_TRUE(sequence.ReadRaw(1, 5, &error).empty());
  EXPECT_EQ(error, "no frame 5");
  EXPECT_TRUE(sequence.ReadRaw(0, kFrames, &error).empty());
}

TEST_F(FourCameras, DisplayImagesAtEveryLevel) {
  const SynchronizedSequence sequence(MakeExperiment());
  std::string error;
  for (int level : {0, 1, 2, 3}) {
    SCOPED_TRACE("level " + std::to_string(level));
    const cv::Mat image = sequence.ReadDisplay(1, 6, level, &error);
    ASSERT_EQ(image.type(), CV_8UC3) << error;
    EXPECT_EQ(image.size(), cv::Size(kWidth >> level, kHeight >> level));
    const uint8_t v = Level(1, 6);
    EXPECT_EQ(cv::norm(image, cv::Mat(image.size(), CV_8UC3, cv::Scalar(v, v, v)), cv::NORM_INF),
              0);
  }
  error.clear();
  EXPECT_TRUE(sequence.ReadDisplay(1, 5, 1, &error).empty());
  EXPECT_FALSE(error.empty());
  error.clear();
  EXPECT_TRUE(sequence.ReadDisplay(3, 2, 0, &error).empty());
  EXPECT_FALSE(error.empty());
}

// Two cameras, "left" reading a/frame_%04d.pgm and "right" b/frame_%04d.pgm, at 50 fps.
Experiment LeftAndRight(const ScratchDir& dir) {
  Experiment e;
  e.name = "left_right";
  e.fps = 50;
  e.base_dir = dir.path().string();
  e.path = dir / "left_right.yaml";
  CameraSpec a;
  a.name = "left";
  a.frames = "a/frame_%04d.pgm";
  CameraSpec b = a;
  b.name = "right";
  b.frames = "b/frame_%04d.pgm";
  e.cameras = {a, b};
  return e;
}

TEST(SynchronizedSequence, DifferentSizesCountsAndRangesAreWarnedAbout) {
  // left: 64x48, frames 0..5 with frame 3 at the wrong size; right: 32x24, frames 2..6.
  ScratchDir dir("sequence");
  for (int k = 0; k <= 5; ++k)
    WritePgm(dir / ("a/" + FrameName(k)),
             Frame(0, k, k == 3 ? cv::Size(32, 24) : cv::Size(64, 48)));
  for (int k = 2; k <= 6; ++k) WritePgm(dir / ("b/" + FrameName(k)), Frame(1, k, {32, 24}));
  const SynchronizedSequence sequence(LeftAndRight(dir));
  EXPECT_EQ(sequence.first_frame(), 0);
  EXPECT_EQ(sequence.last_frame(), 6);
  for (bool decode : {false, true}) {
    SCOPED_TRACE(decode ? "decode" : "headers");
    const CheckReport r = sequence.Check(decode, {}, 2);
    ASSERT_EQ(r.cameras.size(), 2u);
    EXPECT_EQ(r.cameras[0].width, 64);
    EXPECT_EQ(r.cameras[1].width, 32);
    EXPECT_EQ(r.cameras[0].missing, (std::vector<int>{6}));
    EXPECT_EQ(r.cameras[1].missing, (std::vector<int>{0, 1}));
    EXPECT_EQ(r.cameras[0].unreadable, (std::vector<int>{3}));
    ASSERT_EQ(r.cameras[0].problems.size(), 1u);
    EXPECT_NE(r.cameras[0].problems[0].find("left frame 3"), std::string::npos);
    EXPECT_NE(r.cameras[0].problems[0].find("size 32x24 differs from the camera's 64x48"),
              std::string::npos)
        << r.cameras[0].problems[0];
    EXPECT_EQ(r.synchronized_frames, 3);  // 2, 4 and 5 (3 is the wrong size in left)
    ASSERT_EQ(r.warnings.size(), 2u);
    EXPECT_NE(r.warnings[0].find("left and right differ in frame size (64x48 and 32x24)"),
              std::string::npos)
        << r.warnings[0];
    EXPECT_NE(r.warnings[1].find("left and right differ in frame count (6 and 5)"),
              std::string::npos)
        << r.warnings[1];
  }
}

TEST(SynchronizedSequence, MissingFramesNameTheCamera) {
  ScratchDir dir("sequence");
  WritePgm(dir / ("a/" + FrameName(0)), Frame(0, 0));
  const Experiment e = LeftAndRight(dir);
  try {
    SynchronizedSequence sequence(e);
    FAIL() << "no error";
  } catch (const InputError& error) {
    const std::string m = error.what();
    EXPECT_NE(m.find("camera right"), std::string::npos) << m;
    EXPECT_NE(m.find("b/frame_%04d.pgm"), std::string::npos) << m;
  }
}

TEST(SynchronizedSequence, BitDepthDefaultsToTheContainerAndWhiteBalanceIsBgr) {
  ScratchDir dir("sequence");
  WritePgm(dir / ("a/" + FrameName(0)), cv::Mat(4, 4, CV_16UC1, cv::Scalar(1000)));
  WritePgm(dir / ("b/" + FrameName(0)), Frame(0, 0));
  Experiment e;
  e.name = "x";
  e.fps = 50;
  e.base_dir = dir.path().string();
  CameraSpec a;
  a.name = "wide";
  a.frames = "a/frame_%04d.pgm";
  a.white_balance_rgb = {2.0, 1.0, 1.5};
  a.black_level = 64;
  CameraSpec b;
  b.name = "narrow";
  b.frames = "b/frame_%04d.pgm";
  CameraSpec c = b;
  c.name = "ten";
  c.bit_depth = 10;
  e.cameras = {a, b, c};
  const SynchronizedSequence sequence(e);
  EXPECT_EQ(sequence.Correction(0).bit_depth, 16);
  EXPECT_EQ(sequence.Correction(0).black_level, 64.0);
  EXPECT_EQ(sequence.Correction(0).gains_bgr, (std::array<double, 3>{1.5, 1.0, 2.0}));
  EXPECT_EQ(sequence.Correction(1).bit_depth, 8);
  EXPECT_EQ(sequence.Correction(2).bit_depth, 10);
}

}  // namespace
}  // namespace netlab::recon
