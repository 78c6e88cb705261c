// Cameras that moved during a shot: a camera that slid or turned on its mount is named with the
// frames where it moved; a rig at rest, a calibration error the same in every frame and label
// noise are not a move.

#include "libreconstruct/geometry/camera_motion.h"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <random>

namespace netlab::recon {
namespace {

constexpr int kRows = 7, kCols = 7, kFrames = 60;

// A flat 7 x 7 net, 10 cm links, flying across the paper's rig and turning.
Eigen::Vector3d KnotAt(int frame, int k) {
  const double s = frame / 179.0;
  const Eigen::Vector3d local(0.0, (k % kCols - 3) * 0.1, (k / kCols - 3) * 0.1);
  const Eigen::Matrix3d turn =
      Eigen::AngleAxisd(1.5 * s, Eigen::Vector3d(0.3, 0.2, 1.0).normalized()).toRotationMatrix();
  return Eigen::Vector3d(0.9 + 0.5 * s, -0.1 + 0.35 * s, -0.05 + 0.25 * s) + turn * local;
}

// Labels of every knot in every camera with `sigma` px of noise; camera c in frame t seen
// through the pose pose(c, t) (the rig's pose where it returns nothing else).
using PoseAt = std::function<calib::Rigid3d(int camera, int frame, const calib::Rigid3d& rest)>;
LabelSet Labels(const calib::Rig& rig, double sigma, const PoseAt& pose, uint64_t seed = 5) {
  std::vector<std::string> names;
  for (const auto& c : rig.cameras) names.push_back(c.name);
  std::vector<int> frames(kFrames);
  for (int t = 0; t < kFrames; ++t) frames[t] = 100 + t;
  LabelSet labels = LabelSet::Empty(kRows, kCols, names, frames);
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> noise(0.0, sigma);
  for (size_t c = 0; c < names.size(); ++c)
    for (int t = 0; t < kFrames; ++t) {
      calib::Camera camera = rig.cameras[c];
      camera.cam_from_world = pose(static_cast<int>(c), t, camera.cam_from_world);
      for (int k = 0; k < kRows * kCols; ++k) {
        Label& l = labels.at(static_cast<int>(c), t, k);
        l.px = camera.ProjectWorld(KnotAt(t, k)) + Eigen::Vector2d(noise(rng), noise(rng));
        l.source = LabelSource::kManual;
        l.state = LabelState::kAccepted;
      }
    }
  return labels;
}

// The camera's centre moved by `mm` along its own x axis (a slide on its mount).
calib::Rigid3d Slid(const calib::Rigid3d& cam_from_world, double mm) {
  calib::Rigid3d moved = cam_from_world;
  moved.translation.x() -= mm * 1e-3;
  return moved;
}

SequenceOptions Options() {
  SequenceOptions o;
  o.sigma_px = 0.2;
  return o;
}

TEST(CameraMotion, ARigAtRestHasNoMovedCamera) {
  const calib::Rig rig = calib::PaperRig();
  const LabelSet labels = Labels(rig, 0.2, [](int, int, const calib::Rigid3d& r) { return r; });
  const std::vector<CameraMotion> m = DetectCameraMotion(rig, labels, Options());
  ASSERT_EQ(m.size(), rig.cameras.size());
  for (const CameraMotion& c : m) {
    EXPECT_TRUE(c.measured) << c.camera << ": " << c.why;
    EXPECT_TRUE(c.moved.empty()) << c.camera << " moved by " << c.largest_departure_px;
    // The shift is measured to a few hundredths of a pixel.
    for (size_t t = 0; t < c.frame.size(); ++t) EXPECT_LT(c.sigma_px[t], 0.1) << c.camera;
  }
  EXPECT_TRUE(CameraMotionSentences(m).empty());
}

// A calibration that put cam1 2 mm off, the same in every frame: not a move during the shot.
TEST(CameraMotion, ACalibrationErrorTheSameInEveryFrameIsNotAMove) {
  const calib::Rig rig = calib::PaperRig();
  const LabelSet labels = Labels(
      rig, 0.2, [](int c, int, const calib::Rigid3d& r) { return c == 1 ? Slid(r, 2.0) : r; });
  const std::vector<CameraMotion> m = DetectCameraMotion(rig, labels, Options());
  for (const CameraMotion& c : m) EXPECT_TRUE(c.moved.empty()) << c.camera;
  // Its labels do sit off the others' points: the place at the start says so.
  EXPECT_GT(m[1].start_px.norm(), 1.0);
}

// cam2 slides 1.5 mm on its mount at frame 130 (row 30) and stays there: named, from that frame
// to the end, and no other camera with it. Its labels after the slide are under review, as the
// labeling's epipolar check leaves them (on the twin, every one of them): they count.
TEST(CameraMotion, ACameraThatSlidIsNamedWithTheFramesWhereItMoved) {
  const calib::Rig rig = calib::PaperRig();
  LabelSet labels = Labels(rig, 0.2, [](int c, int t, const calib::Rigid3d& r) {
    return c == 2 && t >= 30 ? Slid(r, 1.5) : r;
  });
  for (int t = 30; t < kFrames; ++t)
    for (int k = 0; k < kRows * kCols; ++k) labels.at(2, t, k).state = LabelState::kNeedsReview;
  const std::vector<CameraMotion> m = DetectCameraMotion(rig, labels, Options());
  ASSERT_EQ(m[2].moved.size(), 1u) << m[2].largest_departure_px;
  EXPECT_EQ(m[2].moved[0].first, 130);
  EXPECT_EQ(m[2].moved[0].second, 159);
  EXPECT_GT(m[2].largest_departure_px, 1.0);
  for (int c : {0, 1, 3}) EXPECT_TRUE(m[c].moved.empty()) << m[c].camera;
  const std::vector<std::string> sentences = CameraMotionSentences(m);
  ASSERT_EQ(sentences.size(), 1u);
  EXPECT_NE(sentences[0].find("cam2 moved in frames 130-159"), std::string::npos) << sentences[0];
}

// cam0 shakes, 0.8 mm at 6 Hz (a vibration of the aircraft): named where the shake takes it
// away from where it was at the start, and only it.
TEST(CameraMotion, AShakingCameraIsNamed) {
  const calib::Rig rig = calib::PaperRig();
  const LabelSet labels = Labels(rig, 0.2, [](int c, int t, const calib::Rigid3d& r) {
    return c == 0 ? Slid(r, 0.8 * std::sin(2 * M_PI * 6.0 * t / 179.0)) : r;
  });
  const std::vector<CameraMotion> m = DetectCameraMotion(rig, labels, Options());
  EXPECT_FALSE(m[0].moved.empty());
  EXPECT_GT(m[0].largest_departure_px, 0.5);
  for (int c : {1, 2, 3}) EXPECT_TRUE(m[c].moved.empty()) << m[c].camera;
}

TEST(CameraMotion, ACameraWithoutLabelsIsSaidSo) {
  const calib::Rig rig = calib::PaperRig();
  LabelSet labels = Labels(rig, 0.2, [](int, int, const calib::Rigid3d& r) { return r; });
  for (Label& l : labels.labels[3]) l = Label{};
  const std::vector<CameraMotion> m = DetectCameraMotion(rig, labels, Options());
  EXPECT_FALSE(m[3].measured);
  EXPECT_NE(m[3].why.find("fewer than"), std::string::npos) << m[3].why;
}

}  // namespace
}  // namespace netlab::recon
