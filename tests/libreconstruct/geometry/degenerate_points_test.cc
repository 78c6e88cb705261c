// Degenerate points: a knot seen only by two cameras that face each other across it is flagged
// with its reason instead of counted valid; the knot-track file keeps the flags, the reasons,
// the frame times' spread and the cameras' offsets; the truth comparison is in the truth's frame
// with the degenerate points apart.

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <random>

#include "common/tracks/track_file.h"
#include "libreconstruct/geometry/bundle_adjust.h"
#include "libreconstruct/geometry/track_export.h"

namespace netlab::recon {
namespace {

constexpr int kRows = 5, kCols = 5, kFrames = 6;
constexpr double kFps = 179.0;

Eigen::Vector3d KnotAt(int t, int k) {
  const Eigen::Vector3d local(0.0, (k % kCols - 2) * 0.1, (k / kCols - 2) * 0.1);
  return Eigen::Vector3d(1.0 + 0.5 * t / kFps, 0.0, 0.0) + local;
}

// On the line from cam0 (-1.5, 0.5, 0.5) to cam3 (4, 0.5, 0.5) of the paper's rig, a little off
// it: the two cameras see it nearly head-on.
const Eigen::Vector3d kHeadOn(1.0, 0.49, 0.49);
constexpr int kFrameOfIt = 3, kKnotOfIt = 24;

// Every knot in every camera (noise 0.1 px), except knot kKnotOfIt in frame kFrameOfIt: at
// kHeadOn, seen by cam0 and cam3 only.
LabelSet Labels(const calib::Rig& rig) {
  std::vector<std::string> names;
  for (const auto& c : rig.cameras) names.push_back(c.name);
  std::vector<int> frames(kFrames);
  for (int t = 0; t < kFrames; ++t) frames[t] = 40 + t;
  LabelSet labels = LabelSet::Empty(kRows, kCols, names, frames);
  std::mt19937_64 rng(5);
  std::normal_distribution<double> noise(0.0, 0.1);
  for (size_t c = 0; c < names.size(); ++c)
    for (int t = 0; t < kFrames; ++t)
      for (int k = 0; k < kRows * kCols; ++k) {
        const bool special = t == kFrameOfIt && k == kKnotOfIt;
        if (special && (c == 1 || c == 2)) continue;
        Label& l = labels.at(static_cast<int>(c), t, k);
        l.px = rig.cameras[c].ProjectWorld(special ? kHeadOn : KnotAt(t, k)) +
               Eigen::Vector2d(noise(rng), noise(rng));
        l.source = LabelSource::kManual;
        l.confidence = 1.0f;
        l.state = LabelState::kAccepted;
      }
  return labels;
}

TEST(DegeneratePoints, AHeadOnPairIsFlaggedWithItsReasonNotCountedValid) {
  const calib::Rig rig = calib::PaperRig();
  // The set-up: the point is in front of both cameras and inside their images.
  for (int c : {0, 3}) {
    const Eigen::Vector2d px = rig.cameras[c].ProjectWorld(kHeadOn);
    ASSERT_TRUE(px.allFinite());
    ASSERT_GT(px.minCoeff(), 0.0);
    ASSERT_LT(px.maxCoeff(), 2047.0);
  }
  SequenceOptions options;
  options.adjustment = Adjustment::kNone;
  options.sigma_px = 0.1;
  const SequenceResult r = ReconstructSequence(rig, Labels(rig), options);
  const size_t cell = static_cast<size_t>(kFrameOfIt) * kRows * kCols + kKnotOfIt;
  EXPECT_EQ(r.triangulated, kFrames * kRows * kCols - 1);
  EXPECT_FALSE(r.valid[cell]);
  ASSERT_EQ(r.degenerate.size(), r.valid.size());
  EXPECT_EQ(r.degenerate[cell], 1);
  ASSERT_EQ(r.degenerate_points.size(), 1u);
  const DegeneratePoint& d = r.degenerate_points[0];
  EXPECT_EQ(d.frame, 40 + kFrameOfIt);
  EXPECT_EQ(d.knot, kKnotOfIt);
  EXPECT_GT(d.ray_angle_deg, 170.0);
  EXPECT_GT(d.sigma_m, r.max_sigma_m);
  EXPECT_NEAR(r.max_sigma_m, 10.0 * r.median_sigma_m, 1e-12);
  EXPECT_NE(d.reason.find("the rays of cam0 and cam3 meet at"), std::string::npos) << d.reason;
  EXPECT_NE(d.reason.find("(nearly head-on)"), std::string::npos) << d.reason;
  EXPECT_NE(r.max_sigma_from.find("10 x the median sigma"), std::string::npos) << r.max_sigma_from;
  // Its position and covariance are kept for a reader; its views are no outliers.
  EXPECT_TRUE(r.position[cell].allFinite());
  EXPECT_TRUE(r.outliers.empty());

  // A bound the user gives above its sigma keeps it valid.
  options.max_sigma_m = 2.0 * d.sigma_m;
  const SequenceResult kept = ReconstructSequence(rig, Labels(rig), options);
  EXPECT_TRUE(kept.valid[cell]);
  EXPECT_TRUE(kept.degenerate_points.empty());
  EXPECT_EQ(kept.max_sigma_from, "given");
}

TEST(DegeneratePoints, TheTrackFileKeepsThemAndTheClocks) {
  const calib::Rig rig = calib::PaperRig();
  SequenceOptions options;
  options.adjustment = Adjustment::kNone;
  const SequenceResult r = ReconstructSequence(rig, Labels(rig), options);
  std::vector<double> time;
  for (int t = 0; t < kFrames; ++t) time.push_back(0.5 + t * 0.01);
  KnotTracks tracks = TracksFromSequence(r, time, "test");
  tracks.frame_time_spread_s.assign(kFrames, 1e-5);
  tracks.camera_offset_frames = {0.0, 0.01, 0.3, std::nan("")};
  tracks.camera_offset_sigma_frames = {0.0, 0.002, 0.002, 0.2};
  tracks.camera_offsets_applied = true;
  const std::string path =
      (std::filesystem::temp_directory_path() / "degenerate_points_test.h5").string();
  WriteKnotTracks(path, tracks);
  const KnotTracks back = ReadKnotTracks(path);
  std::filesystem::remove(path);
  EXPECT_EQ(back.time, time);
  EXPECT_EQ(back.degenerate, tracks.degenerate);
  EXPECT_TRUE(back.Degenerate(kFrameOfIt, kKnotOfIt));
  ASSERT_EQ(back.degenerate_points.size(), 1u);
  EXPECT_EQ(back.degenerate_points[0].frame, 40 + kFrameOfIt);
  EXPECT_EQ(back.degenerate_points[0].knot, kKnotOfIt);
  EXPECT_EQ(back.degenerate_points[0].reason, r.degenerate_points[0].reason);
  EXPECT_EQ(back.degenerate_points[0].sigma_m, r.degenerate_points[0].sigma_m);
  EXPECT_EQ(back.degenerate_max_sigma_m, r.max_sigma_m);
  EXPECT_EQ(back.degenerate_bound_from, r.max_sigma_from);
  EXPECT_EQ(back.frame_time_spread_s, tracks.frame_time_spread_s);
  EXPECT_EQ(back.camera_offset_frames[2], 0.3);
  EXPECT_TRUE(std::isnan(back.camera_offset_frames[3]));
  EXPECT_EQ(back.camera_offset_sigma_frames, tracks.camera_offset_sigma_frames);
  EXPECT_TRUE(back.camera_offsets_applied);
}

TEST(DegeneratePoints, TheTruthComparisonIsInTheTruthsFrameWithThemApart) {
  const calib::Rig rig = calib::PaperRig();
  SequenceOptions options;
  options.adjustment = Adjustment::kNone;
  options.sigma_px = 0.1;
  const SequenceResult r = ReconstructSequence(rig, Labels(rig), options);
  const KnotTracks tracks = TracksFromSequence(r, kFps, "test");
  // The truth in another frame: turned 0.2 rad about z and moved 0.3 m.
  const Eigen::Matrix3d turn = Eigen::AngleAxisd(0.2, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  const Eigen::Vector3d shift(0.3, 0.0, 0.0);
  KnotTracks truth;
  for (int f = 30; f < 60; ++f) truth.time.push_back(f / kFps);
  truth.grid = tracks.grid;
  for (int f = 30; f < 60; ++f)
    for (int k = 0; k < kRows * kCols; ++k) {
      // The knot of the head-on view was truly somewhere else: its error is large.
      truth.position.push_back(turn * KnotAt(f - 40, k) + shift);
      truth.valid.push_back(1);
    }
  const TruthComparison c = CompareWithTruth(tracks, truth);
  ASSERT_TRUE(c.aligned);
  EXPECT_EQ(c.points, kFrames * kRows * kCols - 1);
  EXPECT_NEAR(c.rotation_deg, 0.2 * 180 / M_PI, 0.01);
  EXPECT_NEAR(c.translation_m, 0.3, 0.01);
  // The labels' noise (0.1 px: about 0.17 mm in 3D), not the frames' difference of 0.3 m.
  EXPECT_LT(c.rms_m, 3e-4);
  EXPECT_LT(c.max_m, 1e-3);
  EXPECT_GT(c.mean_mahalanobis2, 0.5);
  EXPECT_LT(c.mean_mahalanobis2, 6.0);
  EXPECT_EQ(c.degenerate_points, 1);
  EXPECT_GT(c.degenerate_rms_m, 0.05);
  EXPECT_EQ(c.degenerate_rms_m, c.degenerate_max_m);
}

}  // namespace
}  // namespace netlab::recon
