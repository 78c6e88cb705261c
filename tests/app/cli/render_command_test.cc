// `netlab render` end to end: a short simulation filmed by the paper's rig at reduced scale; the
// output reads with `netlab ingest`, its truth agrees with the rig and the 3D tracks, and the
// rendered foil images calibrate back to the true rig.

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "calibration/rig.h"
#include "common/hdf5_util.h"
#include "common/tracks/track_file.h"
#include "libreconstruct/labels/label_set.h"
#include "tests/app/cli/run_netlab.h"
#include "tests/app/cli/small_shot.h"

namespace {

using netlab::testing::Json;
using netlab::testing::LastJson;
using netlab::testing::RunNetlab;
namespace fs = std::filesystem;
namespace h5 = netlab::h5;

class RenderCommand : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = fs::temp_directory_path() / ("netlab_render_cli_" + std::to_string(getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    std::ofstream(dir_ / "scenario.yaml") << netlab::testing::kSmallShotScenario;
    const auto sim = RunNetlab("simulate " + (dir_ / "scenario.yaml").string() + " --out " +
                               (dir_ / "sim.h5").string() + " --quiet");
    ASSERT_EQ(sim.status, 0) << sim.err;
    render_ = RunNetlab("render --sim " + (dir_ / "sim.h5").string() + " --out " +
                        (dir_ / "shot").string() +
                        " --scale 0.25 --frames 2:9 --calibration-views 12 --json");
  }
  static void TearDownTestSuite() { fs::remove_all(dir_); }
  static std::string Path(const std::string& name) { return (dir_ / name).string(); }

  static inline fs::path dir_;
  static inline netlab::testing::NetlabResult render_;
};

TEST_F(RenderCommand, ReportsFramesCamerasAndVisibleKnots) {
  ASSERT_EQ(render_.status, 0) << render_.err;
  const Json json = LastJson(render_.out);
  EXPECT_EQ(json["frames"].number(), 8);
  EXPECT_EQ(json["cameras"].number(), 4);
  EXPECT_EQ(json["knots"].number(), 36);
  EXPECT_EQ(json["calibration_images"].number(), 48 + 4);  // foil views, one marker image each
  EXPECT_GT(json["wall_s"].number(), 0.0);
  for (const char* camera : {"cam0", "cam1", "cam2", "cam3"}) {
    const Json& visible = json["knots_visible"][camera];
    EXPECT_LE(visible["mean"].number(), 36.0) << camera;
    EXPECT_GT(visible["min"].number(), 0.0) << camera;
  }
  // cam0 and cam1 look at the net from behind the ejector: nothing hides it.
  EXPECT_EQ(json["knots_visible"]["cam0"]["min"].number(), 36);
}

TEST_F(RenderCommand, TheExperimentReadsWithIngest) {
  ASSERT_EQ(render_.status, 0) << render_.err;
  const auto r = RunNetlab("ingest " + Path("shot/experiment.yaml") + " --check --decode --json");
  ASSERT_EQ(r.status, 0) << r.err;
  const Json json = LastJson(r.out);
  EXPECT_EQ(json["synchronized_frames"].number(), 8);
  EXPECT_EQ(json["first_frame"].number(), 2);
  for (const Json& camera : json["cameras"].array()) {
    EXPECT_EQ(camera["width"].number(), 512);
    EXPECT_EQ(camera["height"].number(), 512);
    EXPECT_TRUE(camera["timestamp_gaps"].array().empty());
    EXPECT_TRUE(camera["duplicated"].array().empty());
  }
}

TEST_F(RenderCommand, ACameraRunningLateSeesTheKnotsLaterAndTheTruthSaysSo) {
  const std::string base = "render --sim " + Path("sim.h5") +
                           " --scale 0.25 --frames 2:5 --calibration-views 0 --quiet --out ";
  const auto r = RunNetlab(base + Path("late") + " --camera-time-offset cam2=0.3");
  ASSERT_EQ(r.status, 0) << r.err;
  const netlab::calib::Rig rig = netlab::calib::ReadRig(Path("late/rig_true.yaml"));
  const netlab::KnotTracks sim = netlab::ReadKnotTracks(Path("sim.h5"));
  h5::Id file = h5::OpenFileReadOnly(Path("late/truth.h5"));
  std::vector<double> offsets(4);
  h5::ReadDataset(file.get(), "camera_time_offset_frames", H5T_NATIVE_DOUBLE, offsets.data());
  EXPECT_EQ(offsets, (std::vector<double>{0.0, 0.0, 0.3, 0.0}));
  double moved = 0.0;
  for (int c : {0, 2}) {
    std::vector<double> px(4 * 36 * 2);
    h5::ReadDataset(file.get(), "cameras/" + rig.cameras[c].name + "/knots_px", H5T_NATIVE_DOUBLE,
                    px.data());
    for (int k = 0; k < 36; ++k) {
      // Frame 3 (row 1): the simulation's output 3; cam2 sees it 0.3 frames on.
      const Eigen::Vector3d at_frame = sim.Position(3, k);
      const Eigen::Vector3d late = 0.7 * sim.Position(3, k) + 0.3 * sim.Position(4, k);
      const Eigen::Vector2d got(px[(36 + k) * 2], px[(36 + k) * 2 + 1]);
      const Eigen::Vector2d expected = rig.cameras[c].ProjectWorld(c == 2 ? late : at_frame);
      EXPECT_LT((got - expected).norm(), c == 2 ? 0.02 : 1e-9) << c << " " << k;
      if (c == 2) moved = std::max(moved, (got - rig.cameras[c].ProjectWorld(at_frame)).norm());
    }
  }
  EXPECT_GT(moved, 0.1);
  // Its timestamps do not show it.
  std::ifstream stamps(Path("late/cam2/timestamps.csv"));
  std::string header, row;
  std::getline(stamps, header);
  std::getline(stamps, row);
  EXPECT_EQ(row.substr(0, 2), "2,");
  EXPECT_NEAR(std::stod(row.substr(2)), 2 / 179.0, 1e-9);
  // A camera the rig lacks, or more than a frame: usage errors naming them.
  auto bad = RunNetlab(base + Path("bad") + " --camera-time-offset cam9=0.3");
  EXPECT_EQ(bad.status, 2);
  EXPECT_NE(bad.err.find("the rig has no camera 'cam9'"), std::string::npos) << bad.err;
  bad = RunNetlab(base + Path("bad") + " --camera-time-offset cam2=1.5");
  EXPECT_EQ(bad.status, 2);
  EXPECT_NE(bad.err.find("-1 < D < 1"), std::string::npos) << bad.err;
  EXPECT_FALSE(fs::exists(Path("bad")));
}

TEST_F(RenderCommand, TruePixelsAreTheProjectionsOfTheTrueKnots) {
  ASSERT_EQ(render_.status, 0) << render_.err;
  const netlab::calib::Rig rig = netlab::calib::ReadRig(Path("shot/rig_true.yaml"));
  const netlab::KnotTracks truth = netlab::ReadKnotTracks(Path("shot/truth.h5"));
  const netlab::KnotTracks sim = netlab::ReadKnotTracks(Path("sim.h5"));
  ASSERT_EQ(truth.frames(), 8);
  ASSERT_EQ(truth.knots(), 36);
  // Frame k at time k / 179 s: frame 2 is simulation output 2 (same interval).
  EXPECT_NEAR(truth.time[0], 2 / 179.0, 1e-12);
  EXPECT_LT((truth.Position(0, 7) - sim.Position(2, 7)).norm(), 1e-12);
  const netlab::recon::LabelSet labels = netlab::recon::ReadLabels(Path("shot/labels_true.h5"));
  ASSERT_EQ(labels.rows * labels.cols, 36);
  EXPECT_EQ(labels.frame_index.front(), 2);
  h5::Id file = h5::OpenFileReadOnly(Path("shot/truth.h5"));
  std::vector<int> frame_index(8);
  h5::ReadDataset(file.get(), "frame_index", H5T_NATIVE_INT32, frame_index.data());
  EXPECT_EQ(frame_index.front(), 2);
  EXPECT_EQ(frame_index.back(), 9);
  for (const auto& camera : rig.cameras) {
    std::vector<double> px(8 * 36 * 2);
    std::vector<uint8_t> visibility(8 * 36);
    h5::ReadDataset(file.get(), "cameras/" + camera.name + "/knots_px", H5T_NATIVE_DOUBLE,
                    px.data());
    h5::ReadDataset(file.get(), "cameras/" + camera.name + "/visibility", H5T_NATIVE_UINT8,
                    visibility.data());
    int hidden = 0;
    for (int t = 0; t < 8; ++t)
      for (int k = 0; k < 36; ++k) {
        const Eigen::Vector2d expected = camera.ProjectWorld(truth.Position(t, k));
        EXPECT_NEAR(px[(t * 36 + k) * 2], expected.x(), 1e-9);
        EXPECT_NEAR(px[(t * 36 + k) * 2 + 1], expected.y(), 1e-9);
        const uint8_t v = visibility[t * 36 + k];
        EXPECT_LE(v, 2);
        if (v == 2) {
          EXPECT_FALSE(expected.x() >= -0.5 && expected.x() <= 511.5 && expected.y() >= -0.5 &&
                       expected.y() <= 511.5)
              << camera.name << " knot " << k << " out of view inside the image";
        }
        hidden += v == 1;
      }
    // labels_true.h5 holds exactly the knots this camera sees, at their true pixels.
    const int c = labels.FindCamera(camera.name);
    ASSERT_GE(c, 0) << camera.name;
    for (int t = 0; t < 8; ++t)
      for (int k = 0; k < 36; ++k) {
        const netlab::recon::Label& l = labels.at(c, t, k);
        ASSERT_EQ(l.present(), visibility[t * 36 + k] == 0) << camera.name << " " << t << " " << k;
        if (l.present()) {
          EXPECT_EQ(l.px.x(), px[(t * 36 + k) * 2]);
          EXPECT_EQ(l.state, netlab::recon::LabelState::kAccepted);
        }
      }
    // The target box stands between cam2/cam3 and the net: it hides some knots from them.
    if (camera.name == "cam2" || camera.name == "cam3") {
      EXPECT_GT(hidden, 0) << camera.name;
    } else {
      EXPECT_EQ(hidden, 0) << camera.name;
    }
  }
}

TEST_F(RenderCommand, TheRenderedFoilCalibratesToTheTrueRig) {
  ASSERT_EQ(render_.status, 0) << render_.err;
  std::string images;
  for (const char* camera : {"cam0", "cam1", "cam2", "cam3"})
    images +=
        std::string(" --images ") + camera + "='" + Path("shot/calibration/") + camera + "/*.png'";
  const auto r = RunNetlab("calibrate --board " + Path("shot/calibration/foil.yaml") + images +
                           " --out " + Path("calibrated.yaml") + " --truth " +
                           Path("shot/rig_true.yaml") + " --json --quiet");
  ASSERT_EQ(r.status, 0) << r.err;
  const Json json = LastJson(r.out);
  EXPECT_LT(json["rms_px"].number(), 0.2);
  // 512 x 512 images, 12 views: the calibration's own centre sigma is ~3 mm, and a principal
  // point known to ~1.5 px at f = 727 px is ~0.12 deg of rotation; bounds at about twice those.
  EXPECT_LT(json["truth"]["max_centre_error_m"].number(), 0.006);
  EXPECT_LT(json["truth"]["max_rotation_error_deg"].number(), 0.3);
  for (const Json& camera : json["truth"]["cameras"].array())
    EXPECT_LT(std::abs(camera["fx_error_px"].number()), 3.0) << camera["name"].string();
}

// The marker map on the target's faces puts the rig into the scene's frame (intrinsics given):
// every centre within 3 sigma of the calibration's own uncertainty; the far pair, which sees
// the markers large, within a centimetre.
TEST_F(RenderCommand, TheRenderedMarkerMapPlacesTheRigInTheWorld) {
  ASSERT_EQ(render_.status, 0) << render_.err;
  std::string images;
  for (const char* camera : {"cam0", "cam1", "cam2", "cam3"})
    images += std::string(" --images ") + camera + "='" + Path("shot/calibration/markers/") +
              camera + "/*.png'";
  const auto r = RunNetlab("calibrate --board " + Path("shot/calibration/markers.yaml") + images +
                           " --fix-intrinsics " + Path("shot/rig_true.yaml") + " --out " +
                           Path("markers.yaml") + " --truth " + Path("shot/rig_true.yaml") +
                           " --json --quiet");
  ASSERT_EQ(r.status, 0) << r.err;
  const Json json = LastJson(r.out);
  const auto& cameras = json["cameras"].array();
  const auto& truth = json["truth"]["cameras"].array();
  ASSERT_EQ(truth.size(), 4u);
  for (size_t c = 0; c < 4; ++c) {
    const double error = truth[c]["centre_error_m"].number();
    EXPECT_LT(error, 3.0 * cameras[c]["centre_sigma_m"].number()) << truth[c]["name"].string();
    if (c >= 2) {
      EXPECT_LT(error, 0.01) << truth[c]["name"].string();
    }
  }
}

// A colouring from `netlab color-net` colours the yarns; one for another net size is refused.
TEST_F(RenderCommand, RendersTheYarnColouringOfColorNet) {
  ASSERT_EQ(RunNetlab("color-net --knots 6x6 --out " + Path("c6.yaml") + " --quiet").status, 0);
  ASSERT_EQ(RunNetlab("color-net --knots 5x5 --out " + Path("c5.yaml") + " --quiet").status, 0);
  auto r = RunNetlab("render --sim " + Path("sim.h5") + " --out " + Path("coloured") +
                     " --scale 0.125 --frames 0:1 --calibration-views 0 --coloring " +
                     Path("c6.yaml") + " --json --quiet");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(LastJson(r.out)["frames"].number(), 2);
  r = RunNetlab("render --sim " + Path("sim.h5") + " --out " + Path("wrong") +
                " --scale 0.125 --frames 0:1 --calibration-views 0 --coloring " + Path("c5.yaml"));
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("the colouring has 40 links"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(Path("wrong")));  // refused before anything is written
}

TEST_F(RenderCommand, BadInputIsNamed) {
  auto r = RunNetlab("render --sim " + Path("missing.h5") + " --out " + Path("x"));
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("missing.h5"), std::string::npos) << r.err;
  r = RunNetlab("render --sim " + Path("sim.h5") + " --out " + Path("x") + " --frames 0:5000");
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("outside the simulation"), std::string::npos) << r.err;
  EXPECT_EQ(RunNetlab("render --sim " + Path("sim.h5")).status, 2);  // no --out
  EXPECT_EQ(RunNetlab("render --sim a.h5 --out b --frames 5").status, 2);
  EXPECT_EQ(RunNetlab("render --sim a.h5 --out b --scale 2").status, 2);
  EXPECT_EQ(RunNetlab("render --sim a.h5 --out b --bit-depth 9").status, 2);
  EXPECT_EQ(RunNetlab("render --help").status, 0);
}

}  // namespace
