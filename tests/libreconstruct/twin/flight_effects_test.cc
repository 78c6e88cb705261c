// The flight effects' physics against their formulas (libreconstruct/twin/flight_effects.h):
// the flicker's mean over the exposure against the waveform's integral, the blur circle of a
// point against the thin lens, the camera response of the sensor, the textile panel and the
// moving camera.

#include "libreconstruct/twin/flight_effects.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "calibration/camera.h"

namespace netlab::recon {
namespace {

// The mean of flicker.Intensity over [t - e/2, t + e/2] by the midpoint rule.
double NumericMean(const Flicker& flicker, double t, double e) {
  constexpr int kSteps = 200000;
  double sum = 0.0;
  for (int i = 0; i < kSteps; ++i) sum += flicker.Intensity(t - 0.5 * e + (i + 0.5) * e / kSteps);
  return sum / kSteps;
}

TEST(Flicker, TheExposuresMeanIsTheWaveformsIntegral) {
  const Flicker ripple{100.0, 0.3, 0.0};
  const Flicker pwm{400.0, 0.8, 0.25};
  for (double t : {0.0, 0.0011, 0.0173, 0.4})
    for (double e : {1e-4, 1e-3, 2.7e-3, 0.02}) {
      EXPECT_NEAR(ripple.MeanOverExposure(t, e), NumericMean(ripple, t, e), 1e-6) << t << " " << e;
      EXPECT_NEAR(pwm.MeanOverExposure(t, e), NumericMean(pwm, t, e), 1e-4) << t << " " << e;
    }
  // The mean over whole periods is 1; depth = (max - min) / (max + min).
  EXPECT_NEAR(ripple.MeanOverExposure(0.003, 0.05), 1.0, 1e-12);
  EXPECT_NEAR(pwm.MeanOverExposure(0.003, 0.05), 1.0, 1e-12);
  EXPECT_NEAR(ripple.Intensity(0.0), 1.3, 1e-12);
  EXPECT_NEAR(ripple.Intensity(0.005), 0.7, 1e-12);
  EXPECT_NEAR(pwm.Intensity(0.0001) * 0.2, pwm.Intensity(0.001), 1e-12);
  // Off: exactly 1.
  EXPECT_EQ(Flicker().MeanOverExposure(0.01, 1e-3), 1.0);
}

// A 200 x 200 pinhole camera at the origin looking along +z.
calib::Camera Pinhole(double fx) {
  calib::Camera c;
  c.name = "lens";
  c.intrinsics.width = c.intrinsics.height = 200;
  c.intrinsics.fx = c.intrinsics.fy = fx;
  c.intrinsics.cx = c.intrinsics.cy = 99.5;
  return c;
}

// The variance of the green channel's light about its centroid, per axis (px^2).
double Variance(const cv::Mat& image) {
  double sum = 0.0, sx = 0.0, sy = 0.0, sxx = 0.0, syy = 0.0;
  for (int y = 0; y < image.rows; ++y)
    for (int x = 0; x < image.cols; ++x) {
      const double v = image.at<cv::Vec3f>(y, x)[1];
      sum += v;
      sx += v * x;
      sy += v * y;
      sxx += v * x * x;
      syy += v * y * y;
    }
  const double mx = sx / sum, my = sy / sum;
  return 0.5 * ((sxx / sum - mx * mx) + (syy / sum - my * my));
}

TEST(DepthOfField, TheBlurCircleOfAPointFollowsTheThinLens) {
  // The paper's 16 mm lens (5.5 um pixels: fx = 2909 px) at f/2, focused at 2 m; a 2 mm ball
  // at 1.2, 2 and 4 m.
  const double pitch = 5.5e-6, fx = 0.016 / pitch;
  const DepthOfField dof{2.0, 2.0, pitch};
  const calib::Camera camera = Pinhole(fx);
  for (double d : {1.2, 2.0, 4.0}) {
    const double f = 0.016, aperture = f / 2.0;
    const double c_formula = aperture * std::abs(d - 2.0) / d * f / (2.0 - f) / pitch;
    EXPECT_NEAR(dof.CirclePx(fx, d), c_formula, 1e-9 * c_formula + 1e-12);
    Scene scene;
    scene.balls.push_back({Eigen::Vector3d(0.0, 0.0, d), 0.001, {1, 1, 1}});
    cv::Mat sharp, depth;
    RenderScene(camera, scene, SceneRenderOptions(), 1.0f, &sharp, &depth);
    EXPECT_NEAR(depth.at<float>(100, 100), d - 0.001, 1e-3);
    EXPECT_TRUE(std::isinf(depth.at<float>(0, 0)));
    const cv::Mat blurred = ApplyDepthOfField(sharp, depth, fx, dof);
    // Light is conserved; the variances add: a uniform disc of diameter c has c^2 / 16.
    EXPECT_NEAR(cv::sum(blurred)[1], cv::sum(sharp)[1], 1e-3 * cv::sum(sharp)[1]);
    const double added = Variance(blurred) - Variance(sharp);
    EXPECT_NEAR(added, c_formula * c_formula / 16.0, 0.03 * c_formula * c_formula / 16.0 + 0.02)
        << "d " << d << " m, c " << c_formula << " px";
    if (d == 2.0) {
      EXPECT_EQ(cv::norm(blurred, sharp, cv::NORM_INF), 0.0);
    }
  }
}

TEST(Lamps, TheTargetsShadowEdgeIsWhereTheLampsRayGrazesTheBox) {
  // Camera at the origin looking along +z; a 0.2 m cube at z = 2.5; a lamp 1 m to its -x side;
  // a thick thread along y at x = 0.5 beside the cube. The segment from the thread's point
  // (0.5, y, 2.5) to the lamp (-1, 0, 2.5) leaves the cube's far face x = -0.1 at 0.6 of the
  // way, at height 0.6 y: it grazes the cube's edge at |y| = 0.1 / 0.6, the shadow's edges.
  const calib::Camera camera = Pinhole(300.0);
  Scene scene;
  Box box;
  box.center = {0.0, 0.0, 2.5};
  box.half_extents = {0.1, 0.1, 0.1};
  box.colour = {0.5f, 0.5f, 0.5f};
  scene.boxes.push_back(box);
  scene.threads.push_back({{{0.5, -0.4, 2.5}, {0.5, 0.4, 2.5}}, 0.005, {1, 1, 1}});
  SceneRenderOptions options;
  options.ambient = 0.1;
  options.lamps.push_back({Eigen::Vector3d(-1.0, 0.0, 2.5), 1.0});
  // The shading is taken at the ends of the thread's pieces: 1/2 px pieces resolve the edge.
  options.max_piece_px = 0.5;
  const cv::Mat image = RenderScene(camera, scene, options);
  // The thread's light per row (its image is the column u = 159.5, 1.2 px wide).
  std::vector<double> row_light(200, 0.0);
  for (int v = 0; v < 200; ++v)
    for (int u = 155; u <= 164; ++u) row_light[v] += image.at<cv::Vec3f>(v, u)[1];
  // Lit at row 60 (y = -0.329 m): 0.1 + sqrt(1 - (t . l)^2) / r^2 of the colour; shadowed: 0.1.
  const double lit = row_light[60], dark = row_light[100];
  const Eigen::Vector3d to_lamp =
      Eigen::Vector3d(-1.0, 0.0, 2.5) - Eigen::Vector3d(0.5, (60 - 99.5) / 300.0 * 2.5, 2.5);
  const double along = to_lamp.normalized().y();
  EXPECT_NEAR(dark / lit, 0.1 / (0.1 + std::sqrt(1.0 - along * along) / to_lamp.squaredNorm()),
              0.002);
  // Where the light crosses half way between the two, from the top and from the bottom.
  const double half = 0.5 * (lit + dark);
  auto crossing = [&](int from, int step) {
    for (int v = from;; v += step)
      if (row_light[v + step] < half)
        return v + step * (row_light[v] - half) / (row_light[v] - row_light[v + step]);
  };
  const double edge = 300.0 * (0.1 / 0.6) / 2.5;  // px from the centre row 99.5
  EXPECT_NEAR(crossing(60, 1), 99.5 - edge, 0.5);
  EXPECT_NEAR(crossing(140, -1), 99.5 + edge, 0.5);

  // A face turned to a lamp at the camera shows colour (ambient + power cos / r^2).
  Scene face;
  face.boxes.push_back(box);
  SceneRenderOptions at_camera;
  at_camera.ambient = 0.1;
  at_camera.lamps.push_back({Eigen::Vector3d::Zero(), 2.0});
  const cv::Mat lit_face = RenderScene(camera, face, at_camera);
  EXPECT_NEAR(lit_face.at<cv::Vec3f>(100, 100)[1], 0.5 * (0.1 + 2.0 / (2.4 * 2.4)), 2e-3);
  // A face seen obliquely, lit by a lamp beside it, is lit at every pixel: it does not shadow
  // itself (the -y face of a cube above the camera's axis, rows 158-161).
  Scene oblique;
  Box high = box;
  high.center = {0.0, 0.6, 2.5};
  oblique.boxes.push_back(high);
  SceneRenderOptions beside;
  beside.ambient = 0.1;
  beside.lamps.push_back({Eigen::Vector3d(0.0, -1.0, 2.5), 2.0});
  const cv::Mat top = RenderScene(camera, oblique, beside);
  for (int v = 158; v <= 161; ++v)
    for (int u = 92; u <= 108; ++u)
      EXPECT_GT(top.at<cv::Vec3f>(v, u)[1], 0.5 * (0.1 + 2.0 / (1.6 * 1.6))) << u << " " << v;
  // Glossy: a highlight on top of it, strongest where the half vector meets the normal.
  at_camera.glossy = 0.5;
  const cv::Mat glossy_face = RenderScene(camera, face, at_camera);
  EXPECT_GT(glossy_face.at<cv::Vec3f>(100, 100)[1], lit_face.at<cv::Vec3f>(100, 100)[1] + 0.05);
  EXPECT_GT(glossy_face.at<cv::Vec3f>(100, 100)[1], glossy_face.at<cv::Vec3f>(100, 120)[1]);
}

TEST(CameraResponse, TheSensorRecordsTheResponseFormula) {
  calib::CameraIntrinsics k = Pinhole(100.0).intrinsics;
  const cv::Mat grey(k.height, k.width, CV_32FC3, cv::Scalar(0.2, 0.3, 0.4));
  SensorOptions sensor;
  sensor.bit_depth = 16;
  sensor.response.white_balance = {1.1, 0.9, 1.3};  // B, G, R
  sensor.response.gain = 1.2;
  sensor.response.gamma = 0.8;
  const cv::Mat raw = Expose(grey, k, sensor);
  const double white = sensor.white();
  // RGGB: (0, 0) red, (1, 0) green, (1, 1) blue.
  EXPECT_NEAR(raw.at<uint16_t>(0, 0), std::pow(1.2 * 1.3 * 0.4, 0.8) * white, 1.0);
  EXPECT_NEAR(raw.at<uint16_t>(0, 1), std::pow(1.2 * 0.9 * 0.3, 0.8) * white, 1.0);
  EXPECT_NEAR(raw.at<uint16_t>(1, 1), std::pow(1.2 * 1.1 * 0.2, 0.8) * white, 1.0);

  // Fixed patterns: the same every frame (whatever the noise seed), of the stated spread.
  SensorOptions patterned;
  patterned.bit_depth = 16;
  patterned.bayer = BayerPattern::kNone;
  patterned.response.prnu = 0.02;
  patterned.response.hot_pixels = 0.01;
  patterned.response.pattern_seed = 9;
  const cv::Mat flat(k.height, k.width, CV_32FC3, cv::Scalar(0.5, 0.5, 0.5));
  patterned.seed = 1;
  const cv::Mat a = Expose(flat, k, patterned);
  patterned.seed = 2;
  const cv::Mat b = Expose(flat, k, patterned);
  EXPECT_EQ(cv::norm(a, b, cv::NORM_INF), 0.0);
  int hot = 0;
  double sum = 0.0, sum2 = 0.0;
  int n = 0;
  for (int y = 0; y < k.height; ++y)
    for (int x = 0; x < k.width; ++x) {
      const double v = a.at<uint16_t>(y, x);
      if (v == white) {
        ++hot;
        continue;
      }
      const double rel = v / (0.5 * white) - 1.0;
      sum += rel;
      sum2 += rel * rel;
      ++n;
    }
  EXPECT_NEAR(hot, 0.01 * k.width * k.height, 4.0 * std::sqrt(0.01 * k.width * k.height));
  EXPECT_NEAR(std::sqrt(sum2 / n - (sum / n) * (sum / n)), 0.02, 0.001);

  // Drawn responses are seeded and differ between cameras.
  const auto drawn = DrawCameraResponses(4, 0.1, 7);
  EXPECT_EQ(drawn.size(), 4u);
  EXPECT_NE(drawn[0].gain, drawn[1].gain);
  EXPECT_EQ(DrawCameraResponses(4, 0.1, 7)[3].gamma, drawn[3].gamma);
  EXPECT_TRUE(DrawCameraResponses(2, 0.0, 7)[1].IsIdentity());
}

TEST(Textile, TheBackgroundIsAFoldedWovenPanelAroundItsAlbedo) {
  const calib::CameraIntrinsics k = Pinhole(100.0).intrinsics;
  const cv::Mat panel = TextileBackground(k, 0.1, false, 3);
  cv::Scalar mean, stddev;
  cv::meanStdDev(panel, mean, stddev);
  EXPECT_NEAR(mean[1], 0.1, 0.01);
  EXPECT_GT(stddev[1], 0.005);  // folds and weave, not a flat colour
  // Through the renderer: shown where nothing else is.
  SceneRenderOptions options;
  options.background_image = &panel;
  const cv::Mat image = RenderScene(Pinhole(100.0), Scene(), options);
  EXPECT_EQ(cv::norm(image, panel, cv::NORM_INF), 0.0);
  const cv::Mat cluttered = TextileBackground(k, 0.1, true, 3);
  EXPECT_GT(cluttered.at<cv::Vec3f>(100, 0)[1], 0.5f);  // the rig's profile on the left edge
}

TEST(CameraMotion, AVibrationAndAStepMoveTheCentreByTheAmplitude) {
  calib::Camera camera = Pinhole(100.0);
  camera.cam_from_world.translation = Eigen::Vector3d(0.1, -0.2, 3.0);
  const CameraMotion vibration = DrawCameraMotion(0.002, 50.0, 0.0, 1, 0);
  const CameraMotion step = DrawCameraMotion(0.003, 0.0, 0.01, 1, 1);
  EXPECT_NEAR(vibration.direction.norm(), 1.0, 1e-12);
  for (double t : {0.0, 0.004, 0.0123}) {
    const Eigen::Vector3d moved = vibration.At(camera, t).Center() - camera.Center();
    EXPECT_NEAR((moved - 0.002 * std::sin(2 * std::numbers::pi * 50.0 * t + vibration.phase) *
                             vibration.direction)
                    .norm(),
                0.0, 1e-12);
  }
  EXPECT_NEAR((step.At(camera, 0.0099).Center() - camera.Center()).norm(), 0.0, 1e-12);
  EXPECT_NEAR((step.At(camera, 0.0101).Center() - camera.Center()).norm(), 0.003, 1e-12);
}

}  // namespace
}  // namespace netlab::recon
