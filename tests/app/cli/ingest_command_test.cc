// `netlab ingest` end to end on a small recording written to disk: --check (headers and
// --decode), --to-hdf5 and reading the store back, and bad input.

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <string>

#include "libreconstruct/recording/sequence.h"
#include "tests/app/cli/run_netlab.h"

namespace {

using netlab::testing::Json;
using netlab::testing::LastJson;
using netlab::testing::RunNetlab;
namespace fs = std::filesystem;
namespace recon = netlab::recon;

constexpr int kFrames = 20, kWidth = 64, kHeight = 48;

// Frame k of camera c: a mosaic whose pixels encode (c, k), so any shift is visible.
cv::Mat Frame(int camera, int k) {
  cv::Mat m(kHeight, kWidth, CV_8UC1);
  for (int y = 0; y < kHeight; ++y)
    for (int x = 0; x < kWidth; ++x)
      m.at<uint8_t>(y, x) = static_cast<uint8_t>(10 * k + 3 * camera + (x + y) % 3);
  return m;
}

std::string Name(int k) {
  char buffer[32];
  std::snprintf(buffer, sizeof(buffer), "frame_%04d.pgm", k);
  return buffer;
}

// Four cameras, frames 0..19. cam1 lacks frame 5; cam2's frame 7 is garbage; cam3's frame 9 is
// cut short; cam0's timestamps skip a period after frame 11.
class IngestCommand : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = fs::temp_directory_path() / ("netlab_ingest_cli_" + std::to_string(getpid()));
    fs::remove_all(dir_);
    for (int c = 0; c < 4; ++c) {
      const fs::path cam = dir_ / ("cam" + std::to_string(c));
      fs::create_directories(cam);
      for (int k = 0; k < kFrames; ++k) {
        if (c == 1 && k == 5) continue;
        const std::string file = (cam / Name(k)).string();
        ASSERT_TRUE(cv::imwrite(file, Frame(c, k)));
        if (c == 2 && k == 7) std::ofstream(file, std::ios::binary) << "this is not an image";
        if (c == 3 && k == 9) fs::resize_file(file, fs::file_size(file) / 2);
      }
    }
    std::ofstream times(dir_ / "cam0_times.csv");
    times << "frame_index,time_s\n";
    for (int k = 0; k < kFrames; ++k) times << k << "," << (k + (k > 11 ? 1 : 0)) / 100.0 << "\n";
    times.close();
    std::ofstream yaml(dir_ / "experiment.yaml");
    yaml << "experiment: cli_test\nfps: 100\ncameras:\n";
    for (int c = 0; c < 4; ++c) {
      yaml << "  - name: cam" << c << "\n    frames: cam" << c << "/frame_%04d.pgm\n"
           << "    bayer: RGGB\n";
      if (c == 0) yaml << "    timestamps: cam0_times.csv\n";
    }
  }
  static void TearDownTestSuite() { fs::remove_all(dir_); }

  static std::string Experiment() { return (dir_ / "experiment.yaml").string(); }
  static std::string Path(const std::string& name) { return (dir_ / name).string(); }

  static std::vector<int> Ints(const Json& array) {
    std::vector<int> v;
    for (const Json& j : array.array()) v.push_back(static_cast<int>(j.number()));
    return v;
  }

  static inline fs::path dir_;
};

TEST_F(IngestCommand, CheckReportsEveryCameraAndTheGaps) {
  const auto r = RunNetlab("ingest " + Experiment() + " --check --json");
  ASSERT_EQ(r.status, 0) << r.err;
  const Json json = LastJson(r.out);
  ASSERT_EQ(json["cameras"].array().size(), 4u);
  for (int c = 0; c < 4; ++c) {
    const Json& cam = json["cameras"].array()[c];
    EXPECT_EQ(cam["name"].string(), "cam" + std::to_string(c));
    EXPECT_EQ(cam["frames"].number(), c == 1 ? kFrames - 1 : kFrames);
    EXPECT_EQ(cam["width"].number(), kWidth);
    EXPECT_EQ(cam["height"].number(), kHeight);
    EXPECT_EQ(Ints(cam["missing"]), c == 1 ? std::vector<int>{5} : std::vector<int>{});
  }
  // The headers show the garbage file and the truncated one.
  EXPECT_EQ(Ints(json["cameras"].array()[2]["unreadable"]), std::vector<int>{7});
  EXPECT_EQ(Ints(json["cameras"].array()[3]["unreadable"]), std::vector<int>{9});
  EXPECT_EQ(Ints(json["cameras"].array()[0]["timestamp_gaps"]), std::vector<int>{11});
  EXPECT_EQ(json["synchronized_frames"].number(), kFrames - 3);
  EXPECT_FALSE(json["decoded"].boolean());
  EXPECT_GT(json["decode_fps"].number(), 0.0);
  // The report on stderr names camera, frame and file of each problem.
  EXPECT_NE(r.err.find("cam3 frame 9"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("frame_0009.pgm"), std::string::npos) << r.err;
}

TEST_F(IngestCommand, DecodeReadsEveryFrame) {
  const auto r = RunNetlab("ingest " + Experiment() + " --check --decode --json --quiet");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_TRUE(r.err.empty()) << r.err;
  const Json json = LastJson(r.out);
  EXPECT_TRUE(json["decoded"].boolean());
  EXPECT_EQ(json["synchronized_frames"].number(), kFrames - 3);
  EXPECT_GT(json["decode_fps"].number(), 0.0);
}

TEST_F(IngestCommand, ConvertsToAFrameStoreThatReadsTheSamePixels) {
  const std::string out = Path("store.h5");
  const auto r = RunNetlab("ingest " + Experiment() + " --to-hdf5 " + out + " --compress 1 --json");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.err.find("100%"), std::string::npos) << r.err;  // the progress bar
  const Json json = LastJson(r.out);
  EXPECT_EQ(json["hdf5"]["frames"].number(), kFrames);
  EXPECT_EQ(json["hdf5"]["experiment_file"].string(), Path("store.yaml"));
  ASSERT_TRUE(fs::exists(out));
  EXPECT_FALSE(fs::exists(out + ".partial"));

  // The written experiment reads the store; gaps stay gaps, frames stay in place.
  const auto check = RunNetlab("ingest " + Path("store.yaml") + " --check --decode --json");
  ASSERT_EQ(check.status, 0) << check.err;
  const Json stored = LastJson(check.out);
  EXPECT_EQ(stored["synchronized_frames"].number(), kFrames - 3);
  // The store keeps the timestamps; unreadable source frames are gaps in it.
  EXPECT_EQ(Ints(stored["cameras"].array()[0]["timestamp_gaps"]), std::vector<int>{11});
  EXPECT_EQ(Ints(stored["cameras"].array()[3]["missing"]), std::vector<int>{9});
  recon::SynchronizedSequence original(recon::LoadExperiment(Experiment()));
  recon::SynchronizedSequence converted(recon::LoadExperiment(Path("store.yaml")));
  for (int c = 0; c < 4; ++c)
    for (int k = 0; k < kFrames; ++k) {
      std::string e1, e2;
      const cv::Mat a = original.ReadRaw(c, k, &e1), b = converted.ReadRaw(c, k, &e2);
      ASSERT_EQ(a.empty(), b.empty()) << "cam" << c << " frame " << k << ": " << e1 << " / " << e2;
      if (!a.empty()) {
        EXPECT_EQ(cv::norm(a, b, cv::NORM_INF), 0.0) << "cam" << c << " frame " << k;
      }
    }
}

TEST_F(IngestCommand, BadInputIsNamed) {
  // A pattern that matches nothing names the camera and the pattern.
  std::ofstream(Path("nothing.yaml"))
      << "experiment: x\nfps: 179\ncameras:\n"
         "  - name: camA\n    frames: nowhere/f_%06d.pgm\n    bayer: RGGB\n";
  auto r = RunNetlab("ingest " + Path("nothing.yaml") + " --check");
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("camA"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("nowhere/f_%06d.pgm"), std::string::npos) << r.err;

  // A bad key value names the file, line and key.
  std::ofstream(Path("badbayer.yaml"))
      << "experiment: x\nfps: 179\ncameras:\n"
         "  - name: cam0\n    frames: cam0/frame_%04d.pgm\n    bayer: RGBG\n";
  r = RunNetlab("ingest " + Path("badbayer.yaml") + " --check");
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("badbayer.yaml"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("bayer"), std::string::npos) << r.err;

  r = RunNetlab("ingest " + Path("missing.yaml") + " --check");
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("missing.yaml"), std::string::npos) << r.err;
}

TEST_F(IngestCommand, UsageErrors) {
  EXPECT_EQ(RunNetlab("ingest").status, 2);
  EXPECT_EQ(RunNetlab("ingest " + Experiment()).status, 2);  // neither --check nor --to-hdf5
  EXPECT_EQ(RunNetlab("ingest " + Experiment() + " --decode").status, 2);
  EXPECT_EQ(RunNetlab("ingest " + Experiment() + " --to-hdf5 x.h5 --compress 12").status, 2);
  EXPECT_EQ(RunNetlab("ingest " + Experiment() + " --check --threads zero").status, 2);
  const auto help = RunNetlab("ingest --help");
  EXPECT_EQ(help.status, 0);
  EXPECT_NE(help.out.find("--to-hdf5"), std::string::npos);
  EXPECT_NE(RunNetlab("--help").out.find("ingest"), std::string::npos);
}

}  // namespace
