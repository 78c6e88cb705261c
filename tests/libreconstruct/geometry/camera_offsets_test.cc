// The cameras' clocks: frame times from timestamps (and their bad input), labels moved along
// their track to the frame time, each camera's sub-frame offset estimated from the knots'
// motion, and the reconstruction with the offsets applied.

#include "libreconstruct/geometry/camera_offsets.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "common/yaml_util.h"

namespace netlab::recon {
namespace {

constexpr int kRows = 5, kCols = 5, kFrames = 30;
constexpr double kFps = 179.0;

// A flat 5 x 5 net, 10 cm links, flying at 0.65 m/s across the rig and turning: every camera sees
// its knots move a few pixels a frame. `speed` scales the motion (0: at rest).
Eigen::Vector3d KnotAt(double frame, int k, double speed = 1.0) {
  const double s = speed * frame / kFps;
  const Eigen::Vector3d local(0.0, (k % kCols - 2) * 0.1, (k / kCols - 2) * 0.1);
  const Eigen::Matrix3d turn =
      Eigen::AngleAxisd(1.5 * s, Eigen::Vector3d(0.3, 0.2, 1.0).normalized()).toRotationMatrix();
  return Eigen::Vector3d(0.9 + 0.5 * s, -0.1 + 0.35 * s, -0.05 + 0.25 * s) + turn * local;
}

// Labels of every knot in every camera of the paper's rig, camera c exposed `offset[c]` frames
// late, with Gaussian noise of `sigma` px, and each knot's labels in each camera off by the same
// Gaussian error of `knot_bias` px in every frame (a detector that misplaces a junction the same
// way while it looks the same).
LabelSet Labels(const calib::Rig& rig, const std::vector<double>& offset, double sigma,
                double speed = 1.0, uint64_t seed = 3, double knot_bias = 0.0) {
  std::vector<std::string> names;
  for (const auto& c : rig.cameras) names.push_back(c.name);
  std::vector<int> frames(kFrames);
  for (int t = 0; t < kFrames; ++t) frames[t] = 200 + t;
  LabelSet labels = LabelSet::Empty(kRows, kCols, names, frames);
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> noise(0.0, sigma), bias(0.0, 1.0);
  std::vector<Eigen::Vector2d> knot_error(names.size() * kRows * kCols, Eigen::Vector2d::Zero());
  if (knot_bias > 0.0)
    for (Eigen::Vector2d& e : knot_error) e = knot_bias * Eigen::Vector2d(bias(rng), bias(rng));
  for (size_t c = 0; c < names.size(); ++c)
    for (int t = 0; t < kFrames; ++t)
      for (int k = 0; k < kRows * kCols; ++k) {
        Label& l = labels.at(static_cast<int>(c), t, k);
        l.px = rig.cameras[c].ProjectWorld(KnotAt(t + offset[c], k, speed)) +
               Eigen::Vector2d(noise(rng), noise(rng)) + knot_error[c * kRows * kCols + k];
        l.source = LabelSource::kManual;
        l.confidence = 1.0f;
        l.state = LabelState::kAccepted;
      }
  return labels;
}

double RmsError(const SequenceResult& r) {
  double ss = 0.0;
  int n = 0;
  for (int t = 0; t < kFrames; ++t)
    for (int k = 0; k < kRows * kCols; ++k) {
      const size_t i = static_cast<size_t>(t) * kRows * kCols + k;
      if (!r.valid[i]) continue;
      ss += (r.position[i] - KnotAt(t, k)).squaredNorm();
      ++n;
    }
  return std::sqrt(ss / n);
}

TEST(FrameTimes, MeanOverTheCamerasWithTheirSpread) {
  const std::vector<int> frames = {10, 11, 12};
  // cam0 on time, cam1 0.2 ms late, cam2 without timestamps.
  std::vector<std::map<int, double>> stamps(3);
  for (int f = 9; f <= 13; ++f) {
    stamps[0][f] = f / 100.0;
    stamps[1][f] = f / 100.0 + 2e-4;
  }
  const FrameTimes times = FrameTimesFromTimestamps(frames, 100.0, {"cam0", "cam1", "cam2"}, stamps,
                                                    {"a.csv", "b.csv", ""});
  ASSERT_EQ(times.time_s.size(), 3u);
  EXPECT_NEAR(times.time_s[1], 0.11 + 1e-4, 1e-12);
  EXPECT_NEAR(times.spread_s[2], 2e-4, 1e-12);
  EXPECT_EQ(times.cameras, (std::vector<std::string>{"cam0", "cam1"}));
  // None: frame / fps, no spread, no camera named.
  const FrameTimes none = FrameTimesFromTimestamps(frames, 100.0, {"cam0"}, {{}}, {""});
  EXPECT_NEAR(none.time_s[2], 0.12, 1e-12);
  EXPECT_EQ(none.spread_s[2], 0.0);
  EXPECT_TRUE(none.cameras.empty());
}

// The message of the InputError `f` throws ("" when none).
template <typename F>
std::string ErrorOf(F f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(FrameTimes, RefusesTimestampsThatLackAFrameRunBackOrDisagree) {
  const std::vector<int> frames = {10, 11, 12};
  std::vector<std::map<int, double>> stamps(2);
  for (int f = 10; f <= 12; ++f) stamps[0][f] = stamps[1][f] = f / 100.0;
  auto run = [&] {
    FrameTimesFromTimestamps(frames, 100.0, {"cam0", "cam1"}, stamps, {"a.csv", "b.csv"});
  };
  EXPECT_EQ(ErrorOf(run), "");

  auto short_stamps = stamps;
  short_stamps[1].erase(12);
  std::swap(stamps, short_stamps);
  std::string e = ErrorOf(run);
  EXPECT_NE(e.find("b.csv: camera cam1's timestamps have 2 frames (10..11) and lack 1 of the 3 "
                   "labeled frames (frame 12)"),
            std::string::npos)
      << e;
  std::swap(stamps, short_stamps);

  stamps[0][11] = 0.095;  // before frame 10
  e = ErrorOf(run);
  EXPECT_NE(e.find("a.csv: camera cam0's timestamps go backwards: frame 10 at 0.1 s, frame 11 at "
                   "0.095 s"),
            std::string::npos)
      << e;
  stamps[0][11] = 0.11;

  stamps[1][12] = 0.12 + 0.015;  // 1.5 frames late
  e = ErrorOf(run);
  EXPECT_NE(e.find("the cameras' timestamps of frame 12 disagree by 1.5 frames"), std::string::npos)
      << e;
  EXPECT_NE(e.find("more than one frame at 100 fps"), std::string::npos) << e;
}

TEST(LabelAtFrameTime, FollowsTheTrackBackByTheOffset) {
  // A label moving on a parabola in the camera's frame numbers: exact with both neighbours.
  LabelSet labels = LabelSet::Empty(1, 1, {"cam0"}, {4, 5, 6, 8});
  auto at = [](double s) { return Eigen::Vector2d(100 + 3 * s + 0.5 * s * s, 50 - 2 * s); };
  for (int t = 0; t < 4; ++t) labels.at(0, t, 0).px = at(labels.frame_index[t]);
  for (auto& l : labels.labels[0]) l.state = LabelState::kAccepted;
  std::vector<uint8_t> usable(4, 1);
  Eigen::Vector2d px, velocity;
  ASSERT_TRUE(LabelAtFrameTime(labels, 0, 1, 0, 0.3, usable, &px, &velocity));
  EXPECT_NEAR((px - at(5 - 0.3)).norm(), 0.0, 1e-9);
  EXPECT_NEAR(velocity.x(), 3 + (5 - 0.3), 1e-9);
  // Frame 6 has frame 5 before it, no frame 7 after: the line through 5 and 6.
  ASSERT_TRUE(LabelAtFrameTime(labels, 0, 2, 0, -0.5, usable, &px));
  EXPECT_NEAR((px - (at(6) + 0.5 * (at(6) - at(5)))).norm(), 0.0, 1e-9);
  // Frame 8 has no neighbour at all.
  EXPECT_FALSE(LabelAtFrameTime(labels, 0, 3, 0, 0.2, usable, &px));
}

TEST(EstimateCameraOffsets, FindsACameraRunningLateAndTheReconstructionUndoesIt) {
  const calib::Rig rig = calib::PaperRig();
  const std::vector<double> truth = {0.0, 0.0, 0.3, -0.1};
  const LabelSet labels = Labels(rig, truth, 0.1);
  SequenceOptions options;
  options.adjustment = Adjustment::kNone;
  options.sigma_px = 0.1;
  const OffsetEstimate estimate = EstimateCameraOffsets(rig, labels, options);
  ASSERT_EQ(estimate.cameras.size(), 4u);
  EXPECT_TRUE(estimate.cameras[0].determined);
  EXPECT_EQ(estimate.cameras[0].offset_frames, 0.0);
  for (int c = 1; c < 4; ++c) {
    SCOPED_TRACE(c);
    ASSERT_TRUE(estimate.cameras[c].determined) << estimate.cameras[c].why;
    EXPECT_NEAR(estimate.cameras[c].offset_frames, truth[c], 0.01);
    EXPECT_GT(estimate.cameras[c].sigma_frames, 0.0);
    EXPECT_LT(estimate.cameras[c].sigma_frames, 0.01);
  }

  // Taken as simultaneous, the late cameras pull the points off; moved to the frame time, the
  // points are as good as those of a synchronised rig.
  const double late = RmsError(ReconstructSequence(rig, labels, options));
  SequenceOptions applied = options;
  applied.camera_offset_frames = estimate.Applicable();
  const SequenceResult moved = ReconstructSequence(rig, labels, applied);
  const double synchronised =
      RmsError(ReconstructSequence(rig, Labels(rig, {0, 0, 0, 0}, 0.1), options));
  EXPECT_EQ(moved.offset_unshifted, 0);
  EXPECT_GT(late, 1.5 * synchronised) << late << " vs " << synchronised;
  EXPECT_LT(RmsError(moved), 1.1 * synchronised) << RmsError(moved) << " vs " << synchronised;
}

// Label errors that persist over the frames (each knot's own) do not average out frame by frame:
// the sigma must say so.
TEST(EstimateCameraOffsets, ItsSigmaCoversLabelErrorsThatPersistFromFrameToFrame) {
  const calib::Rig rig = calib::PaperRig();
  const std::vector<double> truth = {0.0, 0.1, -0.2, 0.25};
  SequenceOptions options;
  options.adjustment = Adjustment::kNone;
  options.sigma_px = 0.2;
  double z2 = 0.0;
  int n = 0;
  for (uint64_t seed = 1; seed <= 8; ++seed) {
    const LabelSet labels = Labels(rig, truth, 0.05, 1.0, seed, 0.2);
    const OffsetEstimate estimate = EstimateCameraOffsets(rig, labels, options);
    for (int c = 1; c < 4; ++c) {
      const CameraOffset& o = estimate.cameras[c];
      ASSERT_TRUE(o.determined) << o.why;
      z2 += std::pow((o.offset_frames - truth[c]) / o.sigma_frames, 2);
      ++n;
    }
  }
  // 24 errors in units of their sigma: RMS 1.13 if the sigma were exact (a jackknife over 10
  // groups has its own scatter); measured 1.68 (the residual scatter's sigma alone: about 10).
  EXPECT_LT(std::sqrt(z2 / n), 2.0);
  EXPECT_GT(std::sqrt(z2 / n), 0.5);
}

TEST(EstimateCameraOffsets, ANetAtRestDeterminesNoOffsetAndSaysSo) {
  const calib::Rig rig = calib::PaperRig();
  for (uint64_t seed = 3; seed <= 6; ++seed) {
    const LabelSet labels = Labels(rig, {0, 0, 0, 0}, 0.1, 0.0, seed);
    SequenceOptions options;
    options.sigma_px = 0.1;
    const OffsetEstimate estimate = EstimateCameraOffsets(rig, labels, options);
    for (int c = 1; c < 4; ++c) {
      SCOPED_TRACE(testing::Message() << "seed " << seed << ", camera " << c);
      EXPECT_FALSE(estimate.cameras[c].determined);
      EXPECT_TRUE(std::isnan(estimate.cameras[c].offset_frames));
      EXPECT_GT(estimate.cameras[c].sigma_frames, 0.0);
      EXPECT_NE(estimate.cameras[c].why.find("too little motion to determine it: sigma"),
                std::string::npos)
          << estimate.cameras[c].why;
      EXPECT_EQ(estimate.Applicable()[c], 0.0);
    }
  }
}

}  // namespace
}  // namespace netlab::recon
