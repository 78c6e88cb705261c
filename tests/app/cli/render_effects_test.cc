// `netlab render`'s flight effects end to end on the small shot: every effect off leaves the
// frames byte for byte as they were; the flicker's frame brightness is the waveform's mean over
// the exposure; the cameras' responses and a moving camera's poses are in truth.h5 and the true
// pixels follow the moved pose; bad effect options are usage errors naming them.

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <string>
#include <vector>

#include "calibration/rig.h"
#include "common/hdf5_util.h"
#include "common/tracks/track_file.h"
#include "libreconstruct/twin/flight_effects.h"
#include "tests/app/cli/run_netlab.h"
#include "tests/app/cli/small_shot.h"

namespace {

using netlab::testing::RunNetlab;
namespace fs = std::filesystem;
namespace h5 = netlab::h5;

class RenderEffects : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = fs::temp_directory_path() / ("netlab_render_effects_" + std::to_string(getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    std::ofstream(dir_ / "scenario.yaml") << netlab::testing::kSmallShotScenario;
    const auto sim = RunNetlab("simulate " + (dir_ / "scenario.yaml").string() + " --out " +
                               (dir_ / "sim.h5").string() + " --quiet");
    ASSERT_EQ(sim.status, 0) << sim.err;
  }
  static void TearDownTestSuite() { fs::remove_all(dir_); }
  static std::string Path(const std::string& name) { return (dir_ / name).string(); }
  // Renders frames 2:9 of the small shot at `scale` into `out` with `options`.
  static netlab::testing::NetlabResult Render(const std::string& out, double scale,
                                              const std::string& options) {
    return RunNetlab("render --sim " + Path("sim.h5") + " --out " + Path(out) + " --scale " +
                     std::to_string(scale) + " --frames 2:9 --calibration-views 0 --quiet " +
                     options);
  }
  static cv::Mat Frame(const std::string& shot, const std::string& camera, int k) {
    char name[32];
    std::snprintf(name, sizeof(name), "frame_%06d.pgm", k);
    return cv::imread(Path(shot + "/" + camera + "/" + name), cv::IMREAD_UNCHANGED);
  }

  static inline fs::path dir_;
};

// FNV-1a, 64 bits.
uint64_t Fnv1a(const std::string& bytes, uint64_t hash) {
  for (unsigned char b : bytes) hash = (hash ^ b) * 0x100000001b3ull;
  return hash;
}

TEST_F(RenderEffects, EveryEffectOffLeavesTheFramesByteForByteAsTheyWere) {
  const auto r = Render("plain", 0.1, "");
  ASSERT_EQ(r.status, 0) << r.err;
  uint64_t hash = 0xcbf29ce484222325ull;
  for (const char* camera : {"cam0", "cam1", "cam2", "cam3"})
    for (int k = 2; k <= 9; ++k) {
      char name[32];
      std::snprintf(name, sizeof(name), "/frame_%06d.pgm", k);
      std::ifstream in(Path(std::string("plain/") + camera + name), std::ios::binary);
      const std::string bytes((std::istreambuf_iterator<char>(in)), {});
      ASSERT_FALSE(bytes.empty()) << camera << name;
      hash = Fnv1a(bytes, hash);
    }
  // The checksum of these 32 frames as the renderer wrote them before the flight effects
  // existed (the same scene, rig, noise and seeds).
  EXPECT_EQ(hash, 0xbebf80e91a018648ull);
}

TEST_F(RenderEffects, EachFramesBrightnessIsTheFlickersMeanOverItsExposure) {
  const std::string exact = "--noise 0 --vignetting 0 --bit-depth 16 --exposure 0.002 ";
  ASSERT_EQ(Render("steady", 0.25, exact).status, 0);
  for (const std::string& flicker : {std::string("100:0.3"), std::string("300:0.6:0.25")}) {
    const auto r = Render("flicker", 0.25, exact + "--flicker " + flicker);
    ASSERT_EQ(r.status, 0) << r.err;
    netlab::recon::Flicker expected{100.0, 0.3, 0.0};
    if (flicker != "100:0.3") expected = {300.0, 0.6, 0.25};
    double lowest = 2.0, highest = 0.0;
    for (const char* camera : {"cam0", "cam2"})
      for (int k = 2; k <= 9; ++k) {
        const cv::Mat steady = Frame("steady", camera, k), lit = Frame("flicker", camera, k);
        double max_value = 0.0;
        cv::minMaxLoc(lit, nullptr, &max_value);
        ASSERT_LT(max_value, 65535.0) << "clipped: the ratio would not be the light's";
        const double ratio = cv::sum(lit)[0] / cv::sum(steady)[0];
        const double mean = expected.MeanOverExposure(k / 179.0, 0.002);
        // Rounding to 16 bits: ~1e-5 of the sum.
        EXPECT_NEAR(ratio, mean, 2e-4) << flicker << " " << camera << " frame " << k;
        lowest = std::min(lowest, ratio);
        highest = std::max(highest, ratio);
      }
    EXPECT_GT(highest - lowest, 0.2) << flicker << ": frames differ as a real sequence's do";
  }
}

TEST_F(RenderEffects, TheCamerasResponsesAreInTheTruth) {
  std::ofstream(Path("response.yaml"))
      << "cameras:\n  cam1: {white_balance: [1.2, 1.0, 0.8], gain: 1.5, gamma: 0.9, "
         "hot_pixels: 0.001, seed: 4}\n";
  auto r = Render("responses", 0.1, "--camera-response " + Path("response.yaml"));
  ASSERT_EQ(r.status, 0) << r.err;
  {
    h5::Id file = h5::OpenFileReadOnly(Path("responses/truth.h5"));
    double gain = 0.0, gamma = 0.0, wb[3];
    h5::ReadDataset(file.get(), "cameras/cam1/response/gain", H5T_NATIVE_DOUBLE, &gain);
    h5::ReadDataset(file.get(), "cameras/cam1/response/gamma", H5T_NATIVE_DOUBLE, &gamma);
    h5::ReadDataset(file.get(), "cameras/cam1/response/white_balance", H5T_NATIVE_DOUBLE, wb);
    EXPECT_EQ(gain, 1.5);
    EXPECT_EQ(gamma, 0.9);
    EXPECT_EQ(wb[0], 0.8);  // B, G, R
    EXPECT_EQ(wb[2], 1.2);
    h5::ReadDataset(file.get(), "cameras/cam0/response/gain", H5T_NATIVE_DOUBLE, &gain);
    EXPECT_EQ(gain, 1.0);
  }
  r = Render("varied", 0.1, "--camera-variation 0.1 --seed 3");
  ASSERT_EQ(r.status, 0) << r.err;
  const auto drawn = netlab::recon::DrawCameraResponses(4, 0.1, 3);
  h5::Id file = h5::OpenFileReadOnly(Path("varied/truth.h5"));
  for (int c = 0; c < 4; ++c) {
    double gain = 0.0;
    h5::ReadDataset(file.get(), "cameras/cam" + std::to_string(c) + "/response/gain",
                    H5T_NATIVE_DOUBLE, &gain);
    EXPECT_EQ(gain, drawn[c].gain) << c;
  }
  // A bad response file or both options: errors naming them.
  std::ofstream(Path("bad_response.yaml")) << "cameras:\n  cam1: {gamma: -1}\n";
  r = Render("bad", 0.1, "--camera-response " + Path("bad_response.yaml"));
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("bad_response.yaml: cameras.cam1: gamma -1 must be in (0, 4]"),
            std::string::npos)
      << r.err;
  r = Render("bad", 0.1, "--camera-response " + Path("response.yaml") + " --camera-variation 1");
  EXPECT_EQ(r.status, 2);
  EXPECT_FALSE(fs::exists(Path("bad")));
}

TEST_F(RenderEffects, LampsLightTheShotAndABadLampFileIsNamed) {
  const auto plain = Render("unlit", 0.1, "--noise 0");
  const auto r = Render("lamps", 0.1, "--noise 0 --lamps paper");
  ASSERT_EQ(r.status, 0) << r.err;
  ASSERT_EQ(plain.status, 0) << plain.err;
  EXPECT_GT(cv::norm(Frame("lamps", "cam2", 5), Frame("unlit", "cam2", 5), cv::NORM_INF), 0.0);
  h5::Id file = h5::OpenFileReadOnly(Path("lamps/truth.h5"));
  const std::string effects = h5::ReadStringDataset(file.get(), "effects");
  EXPECT_NE(effects.find("glossy: 0.25"), std::string::npos) << effects;
  EXPECT_NE(effects.find("position: [4, -0.65, 0.5]"), std::string::npos) << effects;
  std::ofstream(Path("lamps.yaml")) << "ambient: 0.2\nlamps:\n  - {position: [1, 2], power: 3}\n";
  const auto bad = Render("bad", 0.1, "--lamps " + Path("lamps.yaml"));
  EXPECT_EQ(bad.status, 1);
  EXPECT_NE(bad.err.find("lamps.yaml: lamps[0]: expected {position: [x, y, z], power}"),
            std::string::npos)
      << bad.err;
  EXPECT_FALSE(fs::exists(Path("bad")));
}

TEST_F(RenderEffects, AMovingCamerasPosesAreInTheTruthAndItsPixelsFollowThem) {
  const auto r = Render("moving", 0.25, "--camera-motion cam0=4:60,cam2=3");
  ASSERT_EQ(r.status, 0) << r.err;
  const netlab::calib::Rig rig = netlab::calib::ReadRig(Path("moving/rig_true.yaml"));
  const netlab::KnotTracks truth = netlab::ReadKnotTracks(Path("moving/truth.h5"));
  h5::Id file = h5::OpenFileReadOnly(Path("moving/truth.h5"));
  for (int c = 0; c < 4; ++c) {
    const std::string group = "cameras/" + rig.cameras[c].name + "/";
    std::vector<double> rotation(8 * 9), translation(8 * 3), px(8 * 36 * 2);
    h5::ReadDataset(file.get(), group + "cam_from_world_rotation", H5T_NATIVE_DOUBLE,
                    rotation.data());
    h5::ReadDataset(file.get(), group + "cam_from_world_translation", H5T_NATIVE_DOUBLE,
                    translation.data());
    h5::ReadDataset(file.get(), group + "knots_px", H5T_NATIVE_DOUBLE, px.data());
    double most = 0.0, moved_px = 0.0;
    std::vector<double> shift(8);
    for (int t = 0; t < 8; ++t) {
      netlab::calib::Camera posed = rig.cameras[c];
      posed.cam_from_world = netlab::calib::Rigid3d(
          Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(&rotation[9 * t]).eval(),
          Eigen::Vector3d(translation[3 * t], translation[3 * t + 1], translation[3 * t + 2]));
      shift[t] = (posed.Center() - rig.cameras[c].Center()).norm();
      most = std::max(most, shift[t]);
      for (int k = 0; k < 36; ++k) {
        const Eigen::Vector2d got(px[(t * 36 + k) * 2], px[(t * 36 + k) * 2 + 1]);
        EXPECT_LT((got - posed.ProjectWorld(truth.Position(t, k))).norm(), 1e-6)
            << c << " " << t << " " << k;
        moved_px =
            std::max(moved_px, (got - rig.cameras[c].ProjectWorld(truth.Position(t, k))).norm());
      }
    }
    if (c == 0) {  // a 4 mm vibration at 60 Hz: within 4 mm, and moving
      EXPECT_LE(most, 0.004 + 1e-12);
      EXPECT_GT(most, 0.002);
      EXPECT_GT(moved_px, 0.1);
    } else if (c == 2) {  // a 3 mm step in the middle of the 8 frames: frames 2-5 still, 6-9 moved
      for (int t = 0; t < 8; ++t) EXPECT_NEAR(shift[t], t < 4 ? 0.0 : 0.003, 1e-9) << t;
    } else {
      EXPECT_EQ(most, 0.0) << c;
    }
  }
  // Bad specs: usage errors naming them.
  auto bad = Render("bad", 0.25, "--camera-motion cam7=1");
  EXPECT_EQ(bad.status, 2);
  EXPECT_NE(bad.err.find("the rig has no camera 'cam7'"), std::string::npos) << bad.err;
  bad = Render("bad", 0.25, "--camera-motion cam0=-1:50");
  EXPECT_EQ(bad.status, 2);
  EXPECT_NE(bad.err.find("amplitude"), std::string::npos) << bad.err;
  bad = Render("bad", 0.25, "--flicker 100");
  EXPECT_EQ(bad.status, 2);
  EXPECT_NE(bad.err.find("--flicker expects HZ:DEPTH"), std::string::npos) << bad.err;
  bad = Render("bad", 0.25, "--f-number 2");
  EXPECT_EQ(bad.status, 2);
  EXPECT_NE(bad.err.find("--f-number and --focus-distance go together"), std::string::npos)
      << bad.err;
}

}  // namespace
