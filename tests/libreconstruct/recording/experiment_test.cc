#include "libreconstruct/recording/experiment.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "common/errors.h"
#include "tests/libreconstruct/test_files.h"

namespace netlab::recon {
namespace {

using testing::ScratchDir;
using testing::WriteBytes;
namespace fs = std::filesystem;

constexpr char kGoodFile[] = R"(experiment: net_a_case1
fps: 179
cameras:
  - name: cam0
    frames: cam0/frame_%06d.pgm
    bayer: RGGB
    timestamps: cam0/timestamps.csv
    bit_depth: 12
    black_level: 64
    white_balance: [1.9, 1.0, 1.6]
  - name: cam1
    frames: store.h5:/cam1
  - name: cam2
    frames: cam2.avi
    bayer: none
    bit_depth: 8
)";

// The message of the InputError parsing `text` throws ("" when none).
std::string ParseError(const std::string& text) {
  try {
    ParseExperiment(text, "exp.yaml", "/data/shot1");
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

// Replaces the first occurrence of `from` in kGoodFile.
std::string GoodFileWith(const std::string& from, const std::string& to) {
  std::string text = kGoodFile;
  const size_t at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  return text.replace(at, from.size(), to);
}

TEST(ParseExperiment, ReadsEveryKey) {
  const Experiment e = ParseExperiment(kGoodFile, "exp.yaml", "/data/shot1");
  EXPECT_EQ(e.name, "net_a_case1");
  EXPECT_EQ(e.fps, 179.0);
  EXPECT_EQ(e.path, "exp.yaml");
  EXPECT_EQ(e.base_dir, "/data/shot1");
  ASSERT_EQ(e.cameras.size(), 3u);

  const CameraSpec& c0 = e.cameras[0];
  EXPECT_EQ(c0.name, "cam0");
  EXPECT_EQ(c0.frames, "cam0/frame_%06d.pgm");  // as written: resolved when opened
  EXPECT_EQ(c0.bayer, BayerPattern::kRGGB);
  EXPECT_EQ(fs::path(c0.timestamps), fs::path("/data/shot1/cam0/timestamps.csv"));
  ASSERT_TRUE(c0.bit_depth.has_value());
  EXPECT_EQ(*c0.bit_depth, 12);
  EXPECT_EQ(c0.black_level, 64.0);
  EXPECT_EQ(c0.white_balance_rgb, (std::array<double, 3>{1.9, 1.0, 1.6}));

  // The optional keys' defaults.
  const CameraSpec& c1 = e.cameras[1];
  EXPECT_EQ(c1.frames, "store.h5:/cam1");
  EXPECT_EQ(c1.bayer, BayerPattern::kNone);
  EXPECT_TRUE(c1.timestamps.empty());
  EXPECT_FALSE(c1.bit_depth.has_value());
  EXPECT_EQ(c1.black_level, 0.0);
  EXPECT_EQ(c1.white_balance_rgb, (std::array<double, 3>{1.0, 1.0, 1.0}));
  EXPECT_EQ(*e.cameras[2].bit_depth, 8);

  EXPECT_EQ(e.Find("cam2"), 2);
  EXPECT_EQ(e.Find("cam3"), -1);

  // Every allowed bit depth.
  for (int depth : {8, 10, 12, 16})
    EXPECT_EQ(*ParseExperiment(GoodFileWith("bit_depth: 12", "bit_depth: " + std::to_string(depth)),
                               "exp.yaml", "")
                   .cameras[0]
                   .bit_depth,
              depth);
}

TEST(ParseExperiment, MissingCamerasNamesTheKey) {
  const std::string m = ParseError("experiment: x\nfps: 100\n");
  EXPECT_NE(m.find("exp.yaml:1: cameras: missing (required)"), std::string::npos) << m;
  const std::string empty = ParseError("experiment: x\nfps: 100\ncameras: []\n");
  EXPECT_NE(empty.find("exp.yaml:3: cameras: expected a list of cameras"), std::string::npos)
      << empty;
  const std::string not_list = ParseError("experiment: x\nfps: 100\ncameras: cam0\n");
  EXPECT_NE(not_list.find("exp.yaml:3: cameras"), std::string::npos) << not_list;
}

TEST(ParseExperiment, BadBayerNameNamesKeyLineAndValue) {
  const std::string m = ParseError(GoodFileWith("bayer: RGGB", "bayer: RGBG"));
  EXPECT_NE(m.find("exp.yaml:6: cameras[0].bayer"), std::string::npos) << m;
  EXPECT_NE(m.find("'RGBG'"), std::string::npos) << m;
}

TEST(ParseExperiment, BitDepthNineIsRejected) {
  const std::string m = ParseError(GoodFileWith("bit_depth: 12", "bit_depth: 9"));
  EXPECT_NE(m.find("exp.yaml:8: cameras[0].bit_depth"), std::string::npos) << m;
  EXPECT_NE(m.find("got 9"), std::string::npos) << m;
  const std::string fraction = ParseError(GoodFileWith("bit_depth: 12", "bit_depth: 12.5"));
  EXPECT_NE(fraction.find("exp.yaml:8: cameras[0].bit_depth"), std::string::npos) << fraction;
}

TEST(ParseExperiment, DuplicatedCameraNameNamesTheSecond) {
  const std::string m = ParseError(GoodFileWith("name: cam1", "name: cam0"));
  EXPECT_NE(m.find("exp.yaml:11: cameras[1].name"), std::string::npos) << m;
  EXPECT_NE(m.find("'cam0' is listed twice"), std::string::npos) << m;
}

TEST(ParseExperiment, FpsMustBePositive) {
  for (const std::string fps : {"0", "-179"}) {
    const std::string m = ParseError(GoodFileWith("fps: 179", "fps: " + fps));
    EXPECT_NE(m.find("exp.yaml:2: fps: must be > 0"), std::string::npos) << m;
  }
  const std::string text = ParseError(GoodFileWith("fps: 179", "fps: fast"));
  EXPECT_NE(text.find("exp.yaml:2: fps: expected a number"), std::string::npos) << text;
  const std::string missing = ParseError(GoodFileWith("fps: 179\n", ""));
  EXPECT_NE(missing.find("fps: missing (required)"), std::string::npos) << missing;
}

TEST(ParseExperiment, OtherBadValuesNameTheirKeyAndLine) {
  struct Case {
    std::string from, to, expected;
  };
  const Case cases[] = {
      {"black_level: 64", "black_level: -1", "exp.yaml:9: cameras[0].black_level: must be >= 0"},
      {"white_balance: [1.9, 1.0, 1.6]", "white_balance: [1.9, 1.0]",
       "exp.yaml:10: cameras[0].white_balance: expected three positive gains"},
      {"white_balance: [1.9, 1.0, 1.6]", "white_balance: [1.9, 0, 1.6]",
       "exp.yaml:10: cameras[0].white_balance: expected three positive gains"},
      {"    frames: store.h5:/cam1\n", "", "cameras[1].frames: missing (required)"},
      {"    bayer: none", "    colour: none", "exp.yaml:15: cameras[2].colour: unknown key"},
      {"fps: 179", "fps: 179\nframerate: 10", "exp.yaml:3: framerate: unknown key"},
      {"cameras:\n", "cameras: [\n", "exp.yaml:"},  // a YAML syntax error
  };
  for (const Case& c : cases) {
    const std::string m = ParseError(GoodFileWith(c.from, c.to));
    EXPECT_NE(m.find(c.expected), std::string::npos) << c.to << " -> " << m;
  }
  EXPECT_NE(ParseError("").find("exp.yaml: file is empty"), std::string::npos);
}

TEST(ReadTimestamps, ReadsHeaderCommentsAndSpacing) {
  ScratchDir dir("experiment");
  WriteBytes(dir / "t.csv",
             "frame_index,time_s\r\n"
             "# exported by the camera software\n"
             "0,0.000\n"
             "\n"
             "1, 0.0055866\r\n"
             "  2 ,0.0111732\n"
             "10,0.0558659\n");
  const auto times = ReadTimestamps(dir / "t.csv");
  ASSERT_EQ(times.size(), 4u);
  EXPECT_EQ(times.at(0), 0.0);
  EXPECT_EQ(times.at(1), 0.0055866);
  EXPECT_EQ(times.at(2), 0.0111732);
  EXPECT_EQ(times.at(10), 0.0558659);

  // No header at all is fine too.
  WriteBytes(dir / "plain.csv", "5,1.5\n6,1.75\n");
  EXPECT_EQ(ReadTimestamps(dir / "plain.csv"), (std::map<int, double>{{5, 1.5}, {6, 1.75}}));
}

TEST(ReadTimestamps, BadLinesNameFileAndLine) {
  ScratchDir dir("experiment");
  const struct {
    std::string text, expected;
  } cases[] = {
      {"frame_index,time_s\n0,0.0\n1,oops\n", ":3: expected 'frame_index,time_s'"},
      {"0,0.0\n1,0.1,7\n", ":2: expected 'frame_index,time_s'"},
      {"0,0.0\n1.5,0.1\n", ":2: frame index must be an integer"},
      {"# c\n0,0.0\n1,0.1\n0,0.2\n", ":4: frame 0 listed twice"},
      {"0,0.0\n1\n", ":2: expected 'frame_index,time_s'"},
  };
  for (const auto& c : cases) {
    WriteBytes(dir / "bad.csv", c.text);
    try {
      ReadTimestamps(dir / "bad.csv");
      ADD_FAILURE() << "no error for " << c.text;
    } catch (const InputError& e) {
      const std::string m = e.what();
      EXPECT_NE(m.find(dir / "bad.csv" + c.expected), std::string::npos) << m;
    }
  }
  EXPECT_THROW(ReadTimestamps(dir / "missing.csv"), InputError);
}

void ExpectSameExperiment(const Experiment& a, const Experiment& b) {
  EXPECT_EQ(a.name, b.name);
  EXPECT_EQ(a.fps, b.fps);
  ASSERT_EQ(a.cameras.size(), b.cameras.size());
  for (size_t i = 0; i < a.cameras.size(); ++i) {
    SCOPED_TRACE(a.cameras[i].name);
    EXPECT_EQ(a.cameras[i].name, b.cameras[i].name);
    EXPECT_EQ(a.cameras[i].frames, b.cameras[i].frames);
    EXPECT_EQ(a.cameras[i].bayer, b.cameras[i].bayer);
    EXPECT_EQ(fs::weakly_canonical(a.cameras[i].timestamps),
              fs::weakly_canonical(b.cameras[i].timestamps));
    EXPECT_EQ(a.cameras[i].timestamps.empty(), b.cameras[i].timestamps.empty());
    EXPECT_EQ(a.cameras[i].bit_depth, b.cameras[i].bit_depth);
    EXPECT_EQ(a.cameras[i].black_level, b.cameras[i].black_level);
    EXPECT_EQ(a.cameras[i].white_balance_rgb, b.cameras[i].white_balance_rgb);
  }
}

TEST(WriteExperiment, LoadsBackTheSameExperiment) {
  ScratchDir dir("experiment");
  WriteBytes(dir / "exp.yaml", kGoodFile);
  const Experiment loaded = LoadExperiment(dir / "exp.yaml");
  EXPECT_EQ(loaded.path, dir / "exp.yaml");
  EXPECT_EQ(loaded.base_dir, dir.path().string());
  WriteExperiment(dir / "copy.yaml", loaded);
  EXPECT_FALSE(fs::exists(dir / "copy.yaml.partial"));
  const Experiment copy = LoadExperiment(dir / "copy.yaml");
  ExpectSameExperiment(loaded, copy);
  EXPECT_EQ(fs::path(copy.cameras[0].timestamps), dir.path() / "cam0/timestamps.csv");
}

TEST(WriteExperiment, AwkwardNamesAndSpecsSurviveTheRoundTrip) {
  // Values YAML would misread unquoted: a spec starting with '%' (frames numbered in the
  // experiment's own folder), a name with ': ' and one starting with '#'.
  Experiment e;
  e.name = "net a: case #1";
  e.fps = 179.5;
  CameraSpec c;
  c.name = "#left";
  c.frames = "%06d.tif";
  c.bayer = BayerPattern::kGBRG;
  c.bit_depth = 10;
  c.black_level = 12.5;
  c.white_balance_rgb = {2.0, 1.0, 1.25};
  e.cameras.push_back(c);
  c = CameraSpec{};
  c.name = "yes";
  c.frames = "[cam1].avi";
  e.cameras.push_back(c);
  ScratchDir dir("experiment");
  WriteExperiment(dir / "exp.yaml", e);
  ExpectSameExperiment(e, LoadExperiment(dir / "exp.yaml"));
}

TEST(WriteExperiment, TimestampsStayFoundWhenLoadedThroughARelativePath) {
  // Load "<relative>/exp.yaml", write it next to itself, load it again: the timestamps file is
  // still the same file (its path is kept relative to the experiment file, not resolved twice).
  ScratchDir scratch("experiment");
  // Deep enough that a path resolved twice cannot land on the right file by climbing to the root.
  fs::path folder = scratch.path();
  for (int i = 0; i < 12; ++i) folder /= std::to_string(i);
  WriteBytes((folder / "exp.yaml").string(), kGoodFile);
  WriteBytes((folder / "cam0/timestamps.csv").string(), "0,0.0\n1,0.01\n");
  const fs::path relative = fs::relative(folder, fs::current_path());
  ASSERT_FALSE(relative.empty());
  ASSERT_FALSE(relative.is_absolute());
  const Experiment loaded = LoadExperiment((relative / "exp.yaml").string());
  EXPECT_EQ(ReadTimestamps(loaded.cameras[0].timestamps).size(), 2u);
  WriteExperiment((relative / "again.yaml").string(), loaded);
  const Experiment again = LoadExperiment((relative / "again.yaml").string());
  ExpectSameExperiment(loaded, again);
  EXPECT_EQ(ReadTimestamps(again.cameras[0].timestamps).size(), 2u);
  // And from another folder the written file still points at the same timestamps.
  fs::create_directories(folder / "sub");
  WriteExperiment((folder / "sub/moved.yaml").string(), loaded);
  const Experiment moved = LoadExperiment((folder / "sub/moved.yaml").string());
  EXPECT_EQ(fs::weakly_canonical(moved.cameras[0].timestamps),
            fs::weakly_canonical(folder / "cam0/timestamps.csv"));
}

TEST(LoadExperiment, MissingFileIsAnInputError) {
  try {
    LoadExperiment("/nonexistent/exp.yaml");
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/exp.yaml"), std::string::npos);
  }
}

}  // namespace
}  // namespace netlab::recon
