// The bad-input suite of `netlab ingest`: every kind of bad experiment file, recording
// or frame store ends in a message naming the file and the key, camera or frame, before any
// library's noise (OpenCV, GStreamer); frames that are only suspicious are reported, each with
// its file.

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <opencv2/imgcodecs.hpp>
#include <string>
#include <vector>

#include "tests/app/cli/bad_input.h"
#include "tests/app/cli/h5_edit.h"
#include "tests/app/cli/run_netlab.h"

namespace netlab::testing {
namespace {

namespace fs = std::filesystem;

constexpr int kFrames = 10, kWidth = 32, kHeight = 24;

// Two cameras of 8-bit mosaics, frames 0..9, cam0 with a timestamps file of every frame: the
// recording every bad input below is a small edit of.
class BadInputIngest : public CommandTest {
 protected:
  BadInputIngest() : CommandTest("bad_input_ingest") {}

  void SetUp() override {
    CommandTest::SetUp();
    for (int c = 0; c < 2; ++c) {
      fs::create_directories(Path("cam" + std::to_string(c)));
      for (int k = 0; k < kFrames; ++k)
        ASSERT_TRUE(cv::imwrite(FramePath(c, k),
                                cv::Mat(kHeight, kWidth, CV_8UC1, cv::Scalar(10 * k + c))));
    }
    std::ofstream times(Path("cam0/timestamps.csv"));
    times << "frame_index,time_s\n";
    for (int k = 0; k < kFrames; ++k) times << k << "," << k / 100.0 << "\n";
  }

  std::string FramePath(int camera, int k) const {
    char name[32];
    std::snprintf(name, sizeof(name), "frame_%04d.pgm", k);
    return Path("cam" + std::to_string(camera) + "/" + name);
  }
  // An experiment file `name` of the two cameras, cam0 given `cam0_extra` (YAML lines, each
  // "    key: value\n"), and the file's top lines replaced by `top` when given.
  std::string Experiment(const std::string& name, const std::string& cam0_extra = "",
                         const std::string& top = "experiment: bad\nfps: 100\n") const {
    std::ofstream(Path(name)) << top << "cameras:\n"
                              << "  - name: cam0\n    frames: cam0/frame_%04d.pgm\n"
                              << "    bayer: RGGB\n    timestamps: cam0/timestamps.csv\n"
                              << cam0_extra << "  - name: cam1\n    frames: cam1/frame_%04d.pgm\n"
                              << "    bayer: RGGB\n";
    return Path(name);
  }
  // A frame store of the recording (store.h5, store.yaml) copied to `name`.h5 and `name`.yaml.
  void Store(const std::string& name) {
    if (!fs::exists(Path("store.h5"))) {
      const NetlabResult r = RunNetlab("ingest " + Experiment("experiment.yaml") + " --to-hdf5 " +
                                       Path("store.h5") + " --quiet");
      ASSERT_EQ(r.status, 0) << r.err;
    }
    fs::copy_file(Path("store.h5"), Path(name + ".h5"));
    std::ifstream in(Path("store.yaml"));
    std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    for (size_t at; (at = text.find("store.h5:")) != std::string::npos;)
      text.replace(at, 8, name + ".h5");
    std::ofstream(Path(name + ".yaml")) << text;
  }
  // Shortens `file`:`dataset` (one entry per frame: uint8 flags or float64 times) to `keep`
  // entries, in its own type.
  void Shorten(const std::string& file, const std::string& dataset, hsize_t keep) {
    auto shorten = [&](auto& v, std::vector<hsize_t>& dims) {
      v.resize(keep);
      dims = {keep};
    };
    if (dataset.size() > 6 && dataset.substr(dataset.size() - 6) == "_valid")
      EditDataset<uint8_t>(Path(file), dataset, H5T_NATIVE_UINT8, shorten);
    else
      EditDataset<double>(Path(file), dataset, H5T_NATIVE_DOUBLE, shorten);
  }
  static std::string Read(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  }
};

TEST_F(BadInputIngest, EveryBadInputIsNamed) {
  Experiment("experiment.yaml");
  std::ofstream(Path("empty.yaml")).close();
  const std::string whole = Read(Path("experiment.yaml"));
  std::ofstream(Path("cut.yaml")) << whole.substr(0, whole.find("bayer: RGGB") + 8);
  std::ofstream(Path("binary.yaml"), std::ios::binary) << std::string("\x89PNG\r\n\x1a\n\0\0", 10);
  Experiment("fps_text.yaml", "", "experiment: bad\nfps: fast\n");
  Experiment("fps_negative.yaml", "", "experiment: bad\nfps: -100\n");
  Experiment("fps_nan.yaml", "", "experiment: bad\nfps: .nan\n");
  std::ofstream(Path("cameras_number.yaml")) << "experiment: bad\nfps: 100\ncameras: 3\n";
  Experiment("unknown_key.yaml", "    exposure: 0.001\n");
  Experiment("bit_depth.yaml", "    bit_depth: 9\n");
  Experiment("black_8.yaml", "    bit_depth: 8\n    black_level: 300\n");
  Experiment("black_auto.yaml", "    black_level: 300\n");
  Experiment("black_negative.yaml", "    black_level: -2\n");
  Experiment("white_balance.yaml", "    white_balance: [1, 0, 1]\n");
  std::ofstream(Path("twice.yaml")) << "experiment: bad\nfps: 100\ncameras:\n"
                                    << "  - {name: cam0, frames: cam0/frame_%04d.pgm}\n"
                                    << "  - {name: cam0, frames: cam1/frame_%04d.pgm}\n";
  std::ofstream(Path("nowhere.yaml")) << "experiment: bad\nfps: 100\ncameras:\n"
                                      << "  - {name: camX, frames: nowhere/f_%06d.pgm}\n";
  std::ofstream(Path("cam0/bad_times.csv")) << "frame_index,time_s\n0,0\n1,soon\n";
  {
    std::string text = whole;
    text.replace(text.find("cam0/timestamps.csv"), 19, "cam0/bad_times.csv");
    std::ofstream(Path("bad_times.yaml")) << text;
    text = whole;
    text.replace(text.find("cam0/timestamps.csv"), 19, "cam0/no_times.csv");
    std::ofstream(Path("no_times.yaml")) << text;
    text = whole;
    text.replace(text.find("bayer: RGGB"), 11, "bayer: RGBG");
    std::ofstream(Path("bayer.yaml")) << text;
  }
  // What a YAML reader takes without a word and netlab would misread: fps twice (179, then -5),
  // a tag on a number, a second document.
  Experiment("fps_twice.yaml", "", "experiment: bad\nfps: 179\nfps: -5\n");
  Experiment("fps_tagged.yaml", "", "experiment: bad\nfps: !fps 179\n");
  std::ofstream(Path("two_documents.yaml")) << whole << "---\nfps: 5\n";
  // Videos OpenCV cannot open: an empty file and random bytes.
  std::ofstream(Path("empty.avi")).close();
  {
    std::ofstream random(Path("random.avi"), std::ios::binary);
    for (int i = 0; i < 4096; ++i) random << static_cast<char>((i * 7919 + 13) % 251);
  }
  std::ofstream(Path("video_empty.yaml")) << "experiment: v\nfps: 179\ncameras:\n"
                                          << "  - {name: cam0, frames: empty.avi}\n";
  std::ofstream(Path("video_random.yaml")) << "experiment: v\nfps: 179\ncameras:\n"
                                           << "  - {name: cam0, frames: random.avi}\n";
  // Frame stores with per-frame datasets of the wrong length, a missing dataset, no HDF5.
  Store("short_valid");
  Shorten("short_valid.h5", "cam0_valid", 5);
  Store("short_times");
  Shorten("short_times.h5", "cam1_timestamps", 9);
  Store("no_dataset");
  {
    std::string text = Read(Path("no_dataset.yaml"));
    text.replace(text.find(":/cam1"), 6, ":/cam7");
    std::ofstream(Path("no_dataset.yaml")) << text;
  }
  std::ofstream(Path("text_store.h5")) << "not HDF5\n";
  std::ofstream(Path("text_store.yaml")) << "experiment: s\nfps: 100\ncameras:\n"
                                         << "  - {name: cam0, frames: 'text_store.h5:/cam0'}\n";

  const std::string check = " --check --quiet";
  ExpectBadInputs(
      {
          {"missing experiment", "ingest {dir}/missing.yaml" + check, 1, {"{dir}/missing.yaml"}},
          {"fps given twice",
           "ingest {dir}/fps_twice.yaml" + check,
           1,
           {"{dir}/fps_twice.yaml:3: fps: given twice, at lines 2 and 3"}},
          {"a tag on fps",
           "ingest {dir}/fps_tagged.yaml" + check,
           1,
           {"{dir}/fps_tagged.yaml:2: fps: the tag '!fps'"}},
          {"a second document",
           "ingest {dir}/two_documents.yaml" + check,
           1,
           {"{dir}/two_documents.yaml:", "a second YAML document"}},
          {"a folder as the experiment",
           "ingest {dir}/cam0" + check,
           1,
           {"{dir}/cam0: is a folder, not a YAML experiment file"}},
          {"empty experiment", "ingest {dir}/empty.yaml" + check, 1, {"{dir}/empty.yaml"}},
          {"truncated experiment", "ingest {dir}/cut.yaml" + check, 1, {"{dir}/cut.yaml"}},
          {"binary experiment", "ingest {dir}/binary.yaml" + check, 1, {"{dir}/binary.yaml"}},
          {"fps not a number",
           "ingest {dir}/fps_text.yaml" + check,
           1,
           {"{dir}/fps_text.yaml:2", "fps"}},
          {"fps negative",
           "ingest {dir}/fps_negative.yaml" + check,
           1,
           {"{dir}/fps_negative.yaml:2", "fps"}},
          {"fps NaN", "ingest {dir}/fps_nan.yaml" + check, 1, {"{dir}/fps_nan.yaml:2", "fps"}},
          {"cameras not a list",
           "ingest {dir}/cameras_number.yaml" + check,
           1,
           {"{dir}/cameras_number.yaml:3", "cameras"}},
          {"unknown key",
           "ingest {dir}/unknown_key.yaml" + check,
           1,
           {"{dir}/unknown_key.yaml", "exposure"}},
          {"bit_depth 9",
           "ingest {dir}/bit_depth.yaml" + check,
           1,
           {"{dir}/bit_depth.yaml:8", "cameras[0].bit_depth", "9"}},
          {"bayer unknown",
           "ingest {dir}/bayer.yaml" + check,
           1,
           {"{dir}/bayer.yaml:6", "cameras[0].bayer", "RGBG"}},
          {"black_level above 8 bits (S10)",
           "ingest {dir}/black_8.yaml" + check,
           1,
           {"{dir}/black_8.yaml:9: cameras[0].black_level: 300 is above the 8-bit white level "
            "255"}},
          {"black_level above the frames' 8 bits (S10)",
           "ingest {dir}/black_auto.yaml" + check,
           1,
           {"{dir}/black_auto.yaml:8: cameras[0].black_level: 300 is above the 8-bit white "
            "level 255",
            "cam0/frame_%04d.pgm"}},
          {"black_level negative",
           "ingest {dir}/black_negative.yaml" + check,
           1,
           {"{dir}/black_negative.yaml:8", "black_level"}},
          {"white_balance zero",
           "ingest {dir}/white_balance.yaml" + check,
           1,
           {"{dir}/white_balance.yaml:8", "white_balance"}},
          {"camera listed twice",
           "ingest {dir}/twice.yaml" + check,
           1,
           {"{dir}/twice.yaml:5", "cam0", "twice"}},
          {"pattern matches nothing",
           "ingest {dir}/nowhere.yaml" + check,
           1,
           {"{dir}/nowhere.yaml", "camX", "nowhere/f_%06d.pgm"}},
          {"timestamps file missing",
           "ingest {dir}/no_times.yaml" + check,
           1,
           {"{dir}/cam0/no_times.csv"}},
          {"timestamps row not a number",
           "ingest {dir}/bad_times.yaml" + check,
           1,
           {"{dir}/cam0/bad_times.csv:3"}},
          {"empty video (U8)",
           "ingest {dir}/video_empty.yaml" + check,
           1,
           {"{dir}/video_empty.yaml: camera cam0: empty.avi: empty file"}},
          {"random bytes as video (U8)",
           "ingest {dir}/video_random.yaml" + check,
           1,
           {"{dir}/video_random.yaml: camera cam0: random.avi: cannot open as a video"}},
          {"store _valid too short (S9)",
           "ingest {dir}/short_valid.yaml" + check,
           1,
           {"{dir}/short_valid.h5:/cam0_valid has 5 entries, /cam0 has 10 frames"}},
          {"store _timestamps too short (S9)",
           "ingest {dir}/short_times.yaml" + check,
           1,
           {"{dir}/short_times.h5:/cam1_timestamps has 9 entries, /cam1 has 10 frames"}},
          {"store dataset missing",
           "ingest {dir}/no_dataset.yaml" + check,
           1,
           {"{dir}/no_dataset.yaml: camera cam1", "/cam7"}},
          {"store not HDF5",
           "ingest {dir}/text_store.yaml" + check,
           1,
           {"{dir}/text_store.yaml: camera cam0", "text_store.h5"}},
          {"store written under a file",
           "ingest {dir}/experiment.yaml --quiet --to-hdf5 "
           "{dir}/cam0/timestamps.csv/x.h5",
           1,
           {"{dir}/cam0/timestamps.csv/x.h5"}},
          {"empty --to-hdf5", "ingest {dir}/experiment.yaml --to-hdf5 ''", 2, {"--to-hdf5"}},
          {"--compress 12",
           "ingest {dir}/experiment.yaml --to-hdf5 {dir}/o.h5 --compress 12",
           2,
           {"--compress"}},
          {"--threads 0", "ingest {dir}/experiment.yaml --check --threads 0", 2, {"--threads"}},
          {"no EXPERIMENT", "ingest --check", 2, {"EXPERIMENT.yaml"}},
          {"neither --check nor --to-hdf5", "ingest {dir}/experiment.yaml", 2, {"--check"}},
          // The store, or the experiment file written beside it, over an input.
          {"--to-hdf5 is the experiment file",
           "ingest {dir}/experiment.yaml --quiet --to-hdf5 {dir}/experiment.yaml",
           1,
           {"--to-hdf5 {dir}/experiment.yaml", "the experiment file {dir}/experiment.yaml"},
           {"{dir}/experiment.yaml"}},
          {"the experiment file beside --to-hdf5 is the experiment file",
           "ingest {dir}/experiment.yaml --quiet --to-hdf5 {dir}/experiment.h5",
           1,
           {"--to-hdf5 (the experiment file written beside it) {dir}/experiment.yaml",
            "the experiment file {dir}/experiment.yaml", "name another --to-hdf5"},
           {"{dir}/experiment.yaml", "{dir}/experiment.h5"}},
          {"--to-hdf5 is a camera's timestamps",
           "ingest {dir}/experiment.yaml --quiet --to-hdf5 {dir}/cam0/timestamps.csv",
           1,
           {"--to-hdf5 {dir}/cam0/timestamps.csv", "the cam0 timestamps file"},
           {"{dir}/cam0/timestamps.csv"}},
      },
      dir_.string());
  EXPECT_FALSE(fs::exists(Path("o.h5")));
}

// A disk that fills while the frame store is written (a file-size limit stands in for it): exit 1
// naming the store, the previous store and its experiment file byte for byte, no partial file.
TEST_F(BadInputIngest, AFullDiskLeavesThePreviousStore) {
  Experiment("experiment.yaml");
  std::ofstream(Path("old.h5")) << "the previous store";
  std::ofstream(Path("old.yaml")) << "the previous experiment file";
  ExpectBadInput({"ingest --to-hdf5 onto a full disk",
                  "ingest {dir}/experiment.yaml --quiet --to-hdf5 {dir}/old.h5",
                  1,
                  {"{dir}/old.h5"},
                  {"{dir}/old.h5", "{dir}/old.yaml"},
                  4096},
                 dir_.string());
}

TEST_F(BadInputIngest, APngNamedPgmIsUnreadableInTheCheckAndTheDecode) {
  // U6: the header check and the decoder follow one rule, the extension's format.
  ASSERT_TRUE(cv::imwrite(Path("frame.png"), cv::Mat(kHeight, kWidth, CV_8UC1, cv::Scalar(7))));
  fs::rename(Path("frame.png"), FramePath(0, 3));
  const std::string experiment = Experiment("experiment.yaml");
  for (const std::string mode : {" --check", " --check --decode"}) {
    SCOPED_TRACE(mode);
    const NetlabResult r = RunNetlab("ingest " + experiment + mode + " --json");
    ASSERT_EQ(r.status, 0) << r.err;  // an unreadable frame is reported, not fatal
    EXPECT_NE(r.err.find("cam0 frame 3 (" + FramePath(0, 3) + "): a PNG file named .pgm"),
              std::string::npos)
        << r.err;
    const Json json = LastJson(r.out);
    EXPECT_EQ(json["cameras"].array()[0]["unreadable"].array().size(), 1u);
    EXPECT_EQ(json["synchronized_frames"].number(), kFrames - 1);
  }
}

TEST_F(BadInputIngest, FramesWithoutATimestampRowAreReported) {
  // X4: frames 7..9 have no row in cam0's timestamps file.
  std::ofstream times(Path("cam0/timestamps.csv"));
  times << "frame_index,time_s\n";
  for (int k = 0; k < 7; ++k) times << k << "," << k / 100.0 << "\n";
  times.close();
  const NetlabResult r = RunNetlab("ingest " + Experiment("experiment.yaml") + " --check --json");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.err.find("no timestamp 7, 8, 9"), std::string::npos) << r.err;
  EXPECT_NE(
      r.err.find("warning: cam0: 3 of 10 frames have no time in " + Path("cam0/timestamps.csv")),
      std::string::npos)
      << r.err;
  const Json json = LastJson(r.out);
  EXPECT_EQ(json["cameras"].array()[0]["untimed"].array().size(), 3u);
  EXPECT_TRUE(json["cameras"].array()[1]["untimed"].array().empty());  // cam1 has no times at all
}

TEST_F(BadInputIngest, AFrameStoreOfTheRightLengthsReadsBack) {
  // The check of the per-frame datasets' lengths passes the store ingest itself writes.
  Store("good");
  const NetlabResult r = RunNetlab("ingest " + Path("good.yaml") + " --check --decode --json");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(LastJson(r.out)["synchronized_frames"].number(), kFrames);
}

}  // namespace
}  // namespace netlab::testing
