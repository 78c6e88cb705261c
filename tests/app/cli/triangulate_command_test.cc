// `netlab triangulate` end to end: labels (labels.h5 and xypts.csv) of a small net seen by the
// paper's rig in, the knot-track file and the DLTdv8 CSVs out, the JSON contract, and bad input.

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <utility>

#include "calibration/rig.h"
#include "common/tracks/track_file.h"
#include "libreconstruct/geometry/track_export.h"
#include "libreconstruct/labels/label_set.h"
#include "tests/app/cli/run_netlab.h"

namespace {

using netlab::testing::Json;
using netlab::testing::LastJson;
using netlab::testing::RunNetlab;
namespace fs = std::filesystem;
namespace recon = netlab::recon;
namespace calib = netlab::calib;

constexpr int kRows = 4, kCols = 4, kFrames = 12;
constexpr double kFps = 179.0;

Eigen::Vector3d KnotAt(int t, int k) {
  return {1.0 + 0.5 * t / kFps, (k % kCols - 1.5) * 0.1, (k / kCols - 1.5) * 0.1};
}

class TriangulateCommand : public netlab::testing::CommandTest {
 protected:
  TriangulateCommand() : CommandTest("triangulate_cli") {}
  void SetUp() override {
    CommandTest::SetUp();
    rig_ = calib::PaperRig();
    calib::WriteRig(Path("rig.yaml"), rig_);
    std::vector<std::string> names;
    for (const auto& c : rig_.cameras) names.push_back(c.name);
    std::vector<int> frames(kFrames);
    for (int t = 0; t < kFrames; ++t) frames[t] = t;
    labels_ = recon::LabelSet::Empty(kRows, kCols, names, frames);
    std::mt19937_64 rng(9);
    std::normal_distribution<double> noise(0.0, 0.2);
    for (int c = 0; c < 4; ++c)
      for (int t = 0; t < kFrames; ++t)
        for (int k = 0; k < kRows * kCols; ++k) {
          recon::Label& l = labels_.at(c, t, k);
          l.px =
              rig_.cameras[c].ProjectWorld(KnotAt(t, k)) + Eigen::Vector2d(noise(rng), noise(rng));
          l.source = recon::LabelSource::kManual;
          l.confidence = 1.0f;
          l.state = recon::LabelState::kAccepted;
        }
    // One mislabel (camera 2, frame 5, knot 6) and one knot seen by a single camera.
    labels_.at(2, 5, 6).px += Eigen::Vector2d(35.0, -20.0);
    for (int c = 1; c < 4; ++c) labels_.at(c, 8, 15) = recon::Label{};
  }
  std::string Base() const {
    return "triangulate --rig " + Path("rig.yaml") + " --knots 4x4 --fps 179 ";
  }

  calib::Rig rig_;
  recon::LabelSet labels_;
};

TEST_F(TriangulateCommand, WritesTracksCsvAndTheContractFields) {
  recon::WriteLabels(Path("labels.h5"), labels_);
  const auto r = RunNetlab(Base() + "--labels " + Path("labels.h5") + " --out " +
                           Path("tracks.h5") + " --csv " + Path("run_") + " --json");
  ASSERT_EQ(r.status, 0) << r.err;
  const Json json = LastJson(r.out);
  for (const char* key :
       {"frames", "points", "triangulated", "reprojection_rms_px", "outliers", "wall_s"})
    EXPECT_TRUE(json.has(key)) << key;
  EXPECT_EQ(json["frames"].number(), kFrames);
  EXPECT_EQ(json["points"].number(), kRows * kCols);
  EXPECT_EQ(json["triangulated"].number(), kFrames * kRows * kCols - 1);
  EXPECT_EQ(json["outliers"].number(), 1);
  EXPECT_LT(json["reprojection_rms_px"].number(), 0.4);

  const netlab::KnotTracks tracks = netlab::ReadKnotTracks(Path("tracks.h5"));
  ASSERT_EQ(tracks.frames(), kFrames);
  ASSERT_EQ(tracks.knots(), kRows * kCols);
  EXPECT_NEAR(tracks.time[3], 3 / kFps, 1e-12);
  ASSERT_EQ(tracks.covariance.size(), tracks.position.size());
  ASSERT_EQ(tracks.reprojection_error_px.size(), tracks.position.size());
  EXPECT_FALSE(tracks.Valid(8, 15));
  for (int t = 0; t < kFrames; ++t)
    for (int k = 0; k < kRows * kCols; ++k)
      if (tracks.Valid(t, k)) {
        EXPECT_LT((tracks.Position(t, k) - KnotAt(t, k)).norm(), 2e-3);
      }
  ASSERT_EQ(tracks.outliers.size(), 1u);
  EXPECT_EQ(tracks.outliers[0].frame, 5);
  EXPECT_EQ(tracks.outliers[0].knot, 6);
  EXPECT_EQ(tracks.camera_names[tracks.outliers[0].camera], rig_.cameras[2].name);

  const auto xyz = recon::ReadXyzPts(Path("run_xyzpts.csv"));
  ASSERT_EQ(static_cast<int>(xyz.size()), kFrames);
  EXPECT_EQ(xyz[2][5], tracks.Position(2, 5));
  EXPECT_TRUE(std::isnan(xyz[8][15].x()));
  const auto res = recon::ReadXyzRes(Path("run_xyzres.csv"));
  EXPECT_EQ(res[2][5], tracks.reprojection_error_px[2 * kRows * kCols + 5]);
}

TEST_F(TriangulateCommand, XyPtsInputGivesTheSameTracks) {
  recon::WriteLabels(Path("labels.h5"), labels_);
  recon::WriteXyPts(Path("xypts.csv"), labels_);
  const std::string common = " --ba none --json --quiet";
  ASSERT_EQ(RunNetlab(Base() + "--labels " + Path("labels.h5") + " --out " + Path("a.h5") + common)
                .status,
            0);
  ASSERT_EQ(RunNetlab(Base() + "--labels " + Path("xypts.csv") + " --out " + Path("b.h5") + common)
                .status,
            0);
  const auto a = netlab::ReadKnotTracks(Path("a.h5"));
  const auto b = netlab::ReadKnotTracks(Path("b.h5"));
  EXPECT_EQ(a.position.size(), b.position.size());
  EXPECT_EQ(a.valid, b.valid);
  for (size_t i = 0; i < a.position.size(); ++i)
    if (a.valid[i]) {
      EXPECT_EQ(a.position[i], b.position[i]);
    }
}

TEST_F(TriangulateCommand, ComparesWithTheTruthAndReportsPriorsAndTheRig) {
  recon::WriteLabels(Path("labels.h5"), labels_);
  netlab::KnotTracks truth;
  for (int t = 0; t < kFrames; ++t) truth.time.push_back(t / kFps);
  for (int k = 0; k < kRows * kCols; ++k) truth.grid.push_back({k / kCols, k % kCols});
  for (int t = 0; t < kFrames; ++t)
    for (int k = 0; k < kRows * kCols; ++k) {
      truth.position.push_back(KnotAt(t, k));
      truth.valid.push_back(1);
    }
  netlab::WriteKnotTracks(Path("truth.h5"), truth);
  const auto r = RunNetlab(Base() + "--labels " + Path("labels.h5") + " --out " +
                           Path("tracks.h5") + " --truth " + Path("truth.h5") +
                           " --ba rig --link-length 0.1 --smooth-sigma 1e-4 --json");
  ASSERT_EQ(r.status, 0) << r.err;
  const Json json = LastJson(r.out);
  EXPECT_LT(json["truth_rms_m"].number(), 1e-3);
  EXPECT_EQ(json["truth_points"].number(), kFrames * kRows * kCols - 1);
  EXPECT_GT(json["link_prior_shift_rms_m"].number(), 0.0);
  EXPECT_GT(json["smoothness_prior_shift_rms_m"].number(), 0.0);
  EXPECT_EQ(json["ba"].string(), "rig");
  // 16 knots over 12 frames do not determine the rig: kept, and said so.
  EXPECT_FALSE(json["rig_adjusted"].boolean());
  EXPECT_NE(r.err.find("NOT adjusted"), std::string::npos) << r.err;
}

TEST_F(TriangulateCommand, TheOutlierThresholdFollowsTheNoiseOrAFixedOneWarns) {
  std::mt19937_64 rng(4);
  std::normal_distribution<double> noise(0.0, 2.0);
  for (auto& camera : labels_.labels)
    for (recon::Label& l : camera)
      if (l.present()) l.px += Eigen::Vector2d(noise(rng), noise(rng));
  recon::WriteLabels(Path("noisy.h5"), labels_);
  // A fixed 4 px threshold at 2 px of noise rejects good labels: said so.
  auto r = RunNetlab(Base() + "--labels " + Path("noisy.h5") + " --out " + Path("t.h5") +
                     " --outlier-px 4 --json");
  ASSERT_EQ(r.status, 0) << r.err;
  const Json fixed = LastJson(r.out);
  ASSERT_FALSE(fixed["warnings"].array().empty());
  EXPECT_NE(fixed["warnings"].array()[0].string().find("--outlier-px"), std::string::npos);
  EXPECT_EQ(fixed["outlier_threshold_px"].number(), 4.0);
  // By default the threshold is 5x the estimated noise: no warning, fewer labels rejected, and
  // the planted mislabel (35 px) still found.
  r = RunNetlab(Base() + "--labels " + Path("noisy.h5") + " --out " + Path("t.h5") + " --json");
  ASSERT_EQ(r.status, 0) << r.err;
  const Json automatic = LastJson(r.out);
  EXPECT_TRUE(automatic["warnings"].array().empty());
  EXPECT_NEAR(automatic["outlier_threshold_px"].number(), 10.0, 1.5);
  EXPECT_LT(automatic["outliers"].number(), fixed["outliers"].number());
  EXPECT_GE(automatic["outliers"].number(), 1);
}

TEST_F(TriangulateCommand, ADegeneratePointIsCountedAndSaidNotValid) {
  // Knot 15 of frame 3 seen only by cam0 and cam3, nearly on the line between them: head-on.
  const Eigen::Vector3d head_on(1.0, 0.49, 0.49);
  for (int c = 0; c < 4; ++c) labels_.at(c, 3, 15) = recon::Label{};
  for (int c : {0, 3}) {
    recon::Label& l = labels_.at(c, 3, 15);
    l.px = rig_.cameras[c].ProjectWorld(head_on);
    l.source = recon::LabelSource::kManual;
    l.state = recon::LabelState::kAccepted;
  }
  recon::WriteLabels(Path("labels.h5"), labels_);
  const auto r = RunNetlab(Base() + "--labels " + Path("labels.h5") + " --out " +
                           Path("tracks.h5") + " --sigma-px 0.2 --json");
  ASSERT_EQ(r.status, 0) << r.err;
  const Json json = LastJson(r.out);
  EXPECT_EQ(json["degenerate_points"].number(), 1);
  EXPECT_EQ(json["triangulated"].number(), kFrames * kRows * kCols - 2);
  EXPECT_GT(json["max_sigma_m"].number(), 0.0);
  EXPECT_NE(r.err.find("1 degenerate point left out: largest sigma over"), std::string::npos)
      << r.err;
  EXPECT_NE(r.err.find("frame 3, knot (3,3): the rays of cam0 and cam3 meet at"), std::string::npos)
      << r.err;
  const netlab::KnotTracks tracks = netlab::ReadKnotTracks(Path("tracks.h5"));
  EXPECT_FALSE(tracks.Valid(3, 15));
  EXPECT_TRUE(tracks.Degenerate(3, 15));
  ASSERT_EQ(tracks.degenerate_points.size(), 1u);
  EXPECT_NE(tracks.degenerate_points[0].reason.find("nearly head-on"), std::string::npos);
  // A bound the user gives over its sigma keeps it.
  const auto kept = RunNetlab(Base() + "--labels " + Path("labels.h5") + " --out " +
                              Path("kept.h5") + " --sigma-px 0.2 --max-sigma-mm 100000 --json");
  ASSERT_EQ(kept.status, 0) << kept.err;
  EXPECT_EQ(LastJson(kept.out)["degenerate_points"].number(), 0);
}

// A net flying across the rig, turning: every camera sees its knots move a few px a frame.
Eigen::Vector3d Moving(double frame, int k) {
  const double s = frame / kFps;
  const Eigen::Vector3d local(0.0, (k % kCols - 1.5) * 0.1, (k / kCols - 1.5) * 0.1);
  const Eigen::Matrix3d turn =
      Eigen::AngleAxisd(1.5 * s, Eigen::Vector3d(0.3, 0.2, 1.0).normalized()).toRotationMatrix();
  return Eigen::Vector3d(0.9 + 0.5 * s, -0.1 + 0.35 * s, -0.05 + 0.25 * s) + turn * local;
}

TEST_F(TriangulateCommand, EstimatesAndAppliesACamerasClockOffset) {
  // cam2 exposes each frame 0.3 frames late; the same labels of a synchronised rig beside them.
  auto write = [&](const std::string& name, double late) {
    std::mt19937_64 rng(2);
    std::normal_distribution<double> noise(0.0, 0.1);
    for (int c = 0; c < 4; ++c)
      for (int t = 0; t < kFrames; ++t)
        for (int k = 0; k < kRows * kCols; ++k)
          labels_.at(c, t, k).px =
              rig_.cameras[c].ProjectWorld(Moving(t + (c == 2 ? late : 0.0), k)) +
              Eigen::Vector2d(noise(rng), noise(rng));
    recon::WriteLabels(Path(name), labels_);
  };
  write("synchronised.h5", 0.0);
  write("labels.h5", 0.3);
  const std::string run = Base() + "--labels " + Path("labels.h5") + " --sigma-px 0.1 --json ";
  auto r = RunNetlab(run + "--out " + Path("estimated.h5") + " --estimate-offsets");
  ASSERT_EQ(r.status, 0) << r.err;
  Json json = LastJson(r.out);
  EXPECT_NEAR(json["camera_offsets_frames"]["cam2"].number(), 0.3, 0.05);
  EXPECT_NEAR(json["camera_offsets_frames"]["cam1"].number(), 0.0, 0.05);
  EXPECT_EQ(json["camera_offsets_frames"]["cam0"].number(), 0.0);
  EXPECT_GT(json["camera_offsets_sigma_frames"]["cam2"].number(), 0.0);
  EXPECT_LT(json["camera_offsets_sigma_frames"]["cam2"].number(), 0.05);
  EXPECT_FALSE(json["camera_offsets_applied"].boolean());
  EXPECT_NE(r.err.find("cam2: +0.3"), std::string::npos) << r.err;
  r = RunNetlab(run + "--out " + Path("applied.h5") + " --apply-offsets");
  ASSERT_EQ(r.status, 0) << r.err;
  json = LastJson(r.out);
  EXPECT_TRUE(json["camera_offsets_applied"].boolean());
  // Moved to the frame time, the points are as good as the synchronised rig's.
  ASSERT_EQ(RunNetlab(Base() + "--labels " + Path("synchronised.h5") +
                      " --sigma-px 0.1 --quiet --out " + Path("synchronised_tracks.h5"))
                .status,
            0);
  const auto synchronised = netlab::ReadKnotTracks(Path("synchronised_tracks.h5"));
  const auto as_is = netlab::ReadKnotTracks(Path("estimated.h5"));
  const auto applied = netlab::ReadKnotTracks(Path("applied.h5"));
  EXPECT_TRUE(applied.camera_offsets_applied);
  ASSERT_EQ(applied.camera_offset_frames.size(), 4u);
  auto rms = [&](const netlab::KnotTracks& tracks) {
    double ss = 0.0;
    int n = 0;
    for (int t = 0; t < kFrames; ++t)
      for (int k = 0; k < kRows * kCols; ++k)
        if (tracks.Valid(t, k)) ss += (tracks.Position(t, k) - Moving(t, k)).squaredNorm(), ++n;
    return std::sqrt(ss / n);
  };
  EXPECT_LT(rms(applied), 1.1 * rms(synchronised)) << rms(applied) << " vs " << rms(synchronised);
  EXPECT_GT(rms(as_is), 1.1 * rms(synchronised)) << rms(as_is) << " vs " << rms(synchronised);
}

TEST_F(TriangulateCommand, TimesComeFromTheRecordingsTimestamps) {
  recon::WriteLabels(Path("labels.h5"), labels_);
  // cam1 0.1 ms behind the others; cam3 without timestamps.
  auto write = [&](const std::string& name, double late_s, int frames, bool backwards = false) {
    std::ofstream out(Path(name));
    out.precision(12);
    out << "frame_index,time_s\n";
    for (int f = 0; f < frames; ++f)
      out << f << "," << (backwards && f == 5 ? 0.0 : 1.0 + f / kFps + late_s) << "\n";
  };
  write("cam0.csv", 0.0, kFrames);
  write("cam1.csv", 1e-4, kFrames);
  write("cam2.csv", 0.0, kFrames);
  auto experiment = [&](const std::string& name, const std::string& cam2) {
    std::ofstream out(Path(name));
    out << "experiment: shot\nfps: 179\ncameras:\n";
    for (const std::string c : {"cam0", "cam1", "cam2", "cam3"}) {
      out << "  - name: " << c << "\n    frames: " << c << "/frame_%06d.pgm\n    bayer: none\n";
      if (c == "cam2")
        out << "    timestamps: " << cam2 << "\n";
      else if (c != "cam3")
        out << "    timestamps: " << c << ".csv\n";
    }
  };
  experiment("experiment.yaml", "cam2.csv");
  const std::string run = Base() + "--labels " + Path("labels.h5") + " --json --out " +
                          Path("tracks.h5") + " --experiment ";
  auto r = RunNetlab(run + Path("experiment.yaml"));
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(LastJson(r.out)["time_from"].string(), "timestamps");
  EXPECT_NEAR(LastJson(r.out)["frame_time_spread_max_s"].number(), 1e-4, 1e-9);
  EXPECT_NE(r.err.find("times from the timestamps of cam0, cam1, cam2"), std::string::npos)
      << r.err;
  const auto tracks = netlab::ReadKnotTracks(Path("tracks.h5"));
  EXPECT_NEAR(tracks.time[4], 1.0 + 4 / kFps + 1e-4 / 3, 1e-9);
  ASSERT_EQ(tracks.frame_time_spread_s.size(), static_cast<size_t>(kFrames));
  EXPECT_NEAR(tracks.frame_time_spread_s[4], 1e-4, 1e-9);

  // Too few frames, going backwards, more than a frame apart: refused, naming the file.
  write("short.csv", 0.0, kFrames - 2);
  write("backwards.csv", 0.0, kFrames, true);
  write("late.csv", 1.5 / kFps, kFrames);
  const std::pair<std::string, std::string> cases[] = {
      {"short.csv", "lack 2 of the 12 labeled frames (frame 10 and more)"},
      {"backwards.csv", "timestamps go backwards: frame 4 at"},
      {"late.csv", "disagree by 1.5 frames"}};
  for (const auto& [file, message] : cases) {
    SCOPED_TRACE(file);
    experiment("bad.yaml", file);
    fs::remove(Path("tracks.h5"));
    r = RunNetlab(run + Path("bad.yaml"));
    EXPECT_EQ(r.status, 1);
    EXPECT_NE(r.err.find(Path(file)), std::string::npos) << r.err;
    EXPECT_NE(r.err.find(message), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(Path("tracks.h5")));
  }
}

TEST_F(TriangulateCommand, BadInputIsNamed) {
  // Labels naming a camera the rig lacks.
  recon::LabelSet other = labels_;
  other.cameras[3] = "camX";
  recon::WriteLabels(Path("other.h5"), other);
  auto r = RunNetlab(Base() + "--labels " + Path("other.h5") + " --out " + Path("t.h5"));
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("camX"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(Path("t.h5")));
  // An xypts.csv naming a point beyond the net.
  std::ofstream(Path("bad.csv")) << "pt1_cam1_X,pt1_cam1_Y,pt99_cam1_X,pt99_cam1_Y\n1,2,3,4\n";
  r = RunNetlab(Base() + "--labels " + Path("bad.csv") + " --out " + Path("t.h5"));
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("pt99"), std::string::npos) << r.err;
  // A labels file of another net's shape.
  recon::WriteLabels(Path("labels.h5"), labels_);
  r = RunNetlab("triangulate --rig " + Path("rig.yaml") + " --knots 5x5 --fps 179 --labels " +
                Path("labels.h5") + " --out " + Path("t.h5"));
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("4 x 4"), std::string::npos) << r.err;
  // Usage errors.
  r = RunNetlab(Base() + "--labels " + Path("labels.h5") + " --out " + Path("t.h5") + " --ba all");
  EXPECT_EQ(r.status, 2);
  r = RunNetlab(Base() + "--labels " + Path("labels.h5") + " --out " + Path("t.h5") +
                " --ba none --link-length 0.1");
  EXPECT_EQ(r.status, 2);
  r = RunNetlab("triangulate --rig " + Path("rig.yaml") + " --knots 4x4 --labels " +
                Path("labels.h5") + " --out " + Path("t.h5"));
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("--fps"), std::string::npos) << r.err;
  r = RunNetlab(Base() + "--labels " + Path("missing.h5") + " --out " + Path("t.h5"));
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("missing.h5"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(Path("t.h5")));
}

}  // namespace
