#include "libreconstruct/twin/render.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <vector>

#include "calibration/camera.h"
#include "calibration/rig.h"

namespace netlab::recon {
namespace {

constexpr BayerPattern kAllPatterns[] = {BayerPattern::kRGGB, BayerPattern::kBGGR,
                                         BayerPattern::kGRBG, BayerPattern::kGBRG};

// A 256 x 256 camera at the world origin looking along +z (world = camera frame), with barrel
// distortion k1 = -0.1 (1.5 px at the image corners) and an off-centre principal point.
calib::Camera DistortedCamera() {
  calib::Camera c;
  c.name = "test";
  c.intrinsics.width = c.intrinsics.height = 256;
  c.intrinsics.fx = c.intrinsics.fy = 300.0;
  c.intrinsics.cx = 129.3;
  c.intrinsics.cy = 126.8;
  c.intrinsics.distortion[0] = -0.1;
  return c;
}

// World point whose image is `pixel` at camera depth `depth` (m).
Eigen::Vector3d Unproject(const calib::Camera& camera, const Eigen::Vector2d& pixel, double depth) {
  const Eigen::Vector2d n = calib::UndistortPoint(camera.intrinsics, pixel);
  return camera.cam_from_world.Inverse() * Eigen::Vector3d(n.x() * depth, n.y() * depth, depth);
}

// Depth (camera z) of a world point.
double Depth(const calib::Camera& camera, const Eigen::Vector3d& p) {
  return (camera.cam_from_world * p).z();
}

// A straight thread from a to b (world), white.
Scene ThreadScene(const Eigen::Vector3d& a, const Eigen::Vector3d& b, double radius,
                  Colour colour = {1, 1, 1}) {
  Scene scene;
  scene.threads.push_back({{a, b}, radius, colour});
  return scene;
}

float Green(const cv::Mat& image, int x, int y) { return image.at<cv::Vec3f>(y, x)[1]; }

// Area of the part of the unit pixel (centred at the origin) where |p . n + u| <= w / 2: a
// straight strip of width w whose centreline passes at signed distance -u from the pixel centre
// along the unit normal n. Exact (Sutherland-Hodgman clipping of the square, shoelace area).
double StripArea(double u, double w, const Eigen::Vector2d& n) {
  std::vector<Eigen::Vector2d> polygon = {{-0.5, -0.5}, {0.5, -0.5}, {0.5, 0.5}, {-0.5, 0.5}};
  // Keeps the part where f(p) = sign (p . n + u) + w / 2 >= 0.
  for (double sign : {1.0, -1.0}) {
    std::vector<Eigen::Vector2d> clipped;
    for (size_t i = 0; i < polygon.size(); ++i) {
      const Eigen::Vector2d& p = polygon[i];
      const Eigen::Vector2d& q = polygon[(i + 1) % polygon.size()];
      const double fp = -sign * (p.dot(n) + u) + 0.5 * w, fq = -sign * (q.dot(n) + u) + 0.5 * w;
      if (fp >= 0) clipped.push_back(p);
      if ((fp >= 0) != (fq >= 0)) clipped.push_back(p + (q - p) * (fp / (fp - fq)));
    }
    polygon = std::move(clipped);
  }
  double area = 0.0;
  for (size_t i = 0; i < polygon.size(); ++i) {
    const Eigen::Vector2d& p = polygon[i];
    const Eigen::Vector2d& q = polygon[(i + 1) % polygon.size()];
    area += p.x() * q.y() - q.x() * p.y();
  }
  return 0.5 * std::abs(area);
}

// The true image of a 3D line near one of its points: centre, unit tangent and normal, and the
// bend (across = bend1 along + bend2 along^2 / 2, px) fitted through the images of points ~3 px
// away on either side. Distortion bends the image of a straight line.
struct LocalCurve {
  Eigen::Vector2d center, tangent, normal;
  double bend1 = 0.0, bend2 = 0.0;
  double width = 0.0;  // of the thread there, px

  // Signed distance of the pixel centre q from the curve (along the normal), px.
  double Across(const Eigen::Vector2d& q) const {
    const double along = (q - center).dot(tangent);
    return (q - center).dot(normal) - (bend1 * along + 0.5 * bend2 * along * along);
  }
  double Along(const Eigen::Vector2d& q) const { return (q - center).dot(tangent); }
};
LocalCurve CurveAt(const calib::Camera& camera, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                   double s, double radius) {
  LocalCurve c;
  const Eigen::Vector3d p = a + s * (b - a);
  c.center = camera.ProjectWorld(p);
  const double ds = 3.0 / (camera.ProjectWorld(b) - camera.ProjectWorld(a)).norm();
  const Eigen::Vector2d plus = camera.ProjectWorld(p + ds * (b - a));
  const Eigen::Vector2d minus = camera.ProjectWorld(p - ds * (b - a));
  c.tangent = (plus - minus).normalized();
  c.normal = Eigen::Vector2d(-c.tangent.y(), c.tangent.x());
  // across = bend1 along + bend2 along^2 / 2 through both neighbours.
  const double l1 = (plus - c.center).dot(c.tangent), a1 = (plus - c.center).dot(c.normal);
  const double l2 = (minus - c.center).dot(c.tangent), a2 = (minus - c.center).dot(c.normal);
  Eigen::Matrix2d m;
  m << l1, 0.5 * l1 * l1, l2, 0.5 * l2 * l2;
  const Eigen::Vector2d bend = m.inverse() * Eigen::Vector2d(a1, a2);
  c.bend1 = bend.x();
  c.bend2 = bend.y();
  c.width = 2.0 * radius * camera.intrinsics.fx / Depth(camera, p);
  return c;
}

// The pixels of `image` near `curve`: within `half_length` px along it and w/2 + 1.5 px across,
// as (signed distance across the true curve, px; intensity).
struct Sample {
  double across;
  double intensity;
};
std::vector<Sample> SamplesNear(const cv::Mat& image, const LocalCurve& curve, double half_length) {
  const double reach = 0.5 * curve.width + 1.5, box = std::max(reach, half_length) + 1.0;
  std::vector<Sample> samples;
  for (int y = static_cast<int>(std::floor(curve.center.y() - box));
       y <= static_cast<int>(std::ceil(curve.center.y() + box)); ++y)
    for (int x = static_cast<int>(std::floor(curve.center.x() - box));
         x <= static_cast<int>(std::ceil(curve.center.x() + box)); ++x) {
      const Eigen::Vector2d q(x, y);
      const double across = curve.Across(q);
      if (std::abs(curve.Along(q)) > half_length || std::abs(across) > reach) continue;
      samples.push_back({across, Green(image, x, y)});
    }
  return samples;
}

// Sub-pixel peak of the thread across `curve`: the shift c of the thread's exact area profile
// (StripArea, known width, unit intensity) that fits the samples best in least squares; a search
// on [-0.6, 0.6] in steps of 0.05 refined by golden section to 1e-4 px.
double FitShift(const std::vector<Sample>& samples, const LocalCurve& curve) {
  auto cost = [&](double c) {
    double e = 0.0;
    for (const Sample& s : samples) {
      const double r = s.intensity - StripArea(s.across - c, curve.width, curve.normal);
      e += r * r;
    }
    return e;
  };
  double best = 0.0, best_cost = cost(0.0);
  for (double c = -0.6; c <= 0.6; c += 0.05)
    if (const double e = cost(c); e < best_cost) best_cost = e, best = c;
  double lo = best - 0.05, hi = best + 0.05;
  const double g = 0.5 * (std::sqrt(5.0) - 1.0);
  double m1 = hi - g * (hi - lo), m2 = lo + g * (hi - lo), c1 = cost(m1), c2 = cost(m2);
  while (hi - lo > 1e-4) {
    if (c1 < c2) {
      hi = m2, m2 = m1, c2 = c1, m1 = hi - g * (hi - lo), c1 = cost(m1);
    } else {
      lo = m1, m1 = m2, c1 = c2, m2 = lo + g * (hi - lo), c2 = cost(m2);
    }
  }
  return 0.5 * (lo + hi);
}

double Rms(const std::vector<double>& v) {
  double s = 0.0;
  for (double x : v) s += x * x;
  return std::sqrt(s / v.size());
}
double Mean(const std::vector<double>& v) {
  double s = 0.0;
  for (double x : v) s += x;
  return s / v.size();
}

// Straight threads at several image angles, sub-pixel positions and depths (the depth grows by
// 30 % along each, so the width shrinks), through the hand-made distorted camera and the paper
// rig's cam0 at 1/4 scale (512 px).
struct ThreadCase {
  const calib::Camera* camera;
  double degrees;
  Eigen::Vector3d a, b;
};
std::vector<ThreadCase> ThreadCases(const calib::Camera& distorted, const calib::Camera& paper) {
  std::vector<ThreadCase> cases;
  for (const calib::Camera* camera : {&distorted, &paper}) {
    const double cx = camera->intrinsics.cx, cy = camera->intrinsics.cy;
    const double half = 0.45 * camera->intrinsics.width;
    for (double degrees : {0.0, 17.0, 45.0, 71.0, 90.0, 133.0})
      for (double shift : {0.0, 0.25, 0.5}) {
        const double angle = degrees * std::numbers::pi / 180.0;
        const Eigen::Vector2d direction(std::cos(angle), std::sin(angle));
        const Eigen::Vector2d normal(-direction.y(), direction.x());
        // Through a point 30 px off the principal point (where distortion bends the line).
        const Eigen::Vector2d middle =
            Eigen::Vector2d(cx + 13.0, cy - 27.0) + (30.0 + shift) * normal;
        const double depth = camera == &distorted ? 2.0 : 2.5;
        cases.push_back({camera, degrees, Unproject(*camera, middle - half * direction, depth),
                         Unproject(*camera, middle + half * direction, 1.3 * depth)});
      }
  }
  return cases;
}

// Renders a case with a thread `width_px` wide at its start; calls f(image, curve) every `step`
// px along its image where it is at least 12 px inside the image.
template <typename F>
void ForEachCrossSection(const ThreadCase& c, double width_px, double step, F&& f) {
  const calib::Camera& camera = *c.camera;
  const double radius = width_px * Depth(camera, c.a) / (2.0 * camera.intrinsics.fx);
  const cv::Mat image = RenderScene(camera, ThreadScene(c.a, c.b, radius), SceneRenderOptions());
  const double length_px = (camera.ProjectWorld(c.b) - camera.ProjectWorld(c.a)).norm();
  const int steps = static_cast<int>(length_px / step);
  const int w = camera.intrinsics.width, h = camera.intrinsics.height;
  for (int i = 1; i < steps; ++i) {
    const LocalCurve curve = CurveAt(camera, c.a, c.b, double(i) / steps, radius);
    if (curve.center.x() < 12 || curve.center.y() < 12 || curve.center.x() > w - 13 ||
        curve.center.y() > h - 13)
      continue;
    f(image, curve);
  }
}

TEST(RenderScene, ThreadPixelsHoldTheAreaOfTheTrueThreadInThem) {
  // Every pixel near the thread holds the exact area of the true thread (the strip of width w
  // about the true projection of its centreline) inside it. A centreline off by e px would
  // change the pixels on the thread's edges by ~e.
  const calib::Camera distorted = DistortedCamera();
  const calib::Camera paper = calib::PaperRig(0.25).cameras[0];
  for (double width : {0.7, 3.0}) {
    double worst = 0.0;
    int pixels = 0;
    for (const ThreadCase& c : ThreadCases(distorted, paper))
      ForEachCrossSection(c, width, 11.0, [&](const cv::Mat& image, const LocalCurve& curve) {
        for (const Sample& s : SamplesNear(image, curve, 0.5)) {
          worst = std::max(worst,
                           std::abs(s.intensity - StripArea(s.across, curve.width, curve.normal)));
          ++pixels;
        }
      });
    // Measured: 0.0004 (w 0.7) and 0.0010 (w 3) at most, over 3824 and 5996 pixels.
    EXPECT_LT(worst, 0.005) << "width " << width;
    EXPECT_GT(pixels, 1000);
    std::printf("width %.1f px: largest difference from the true area %.4f over %d pixels\n", width,
                worst, pixels);
  }
}

TEST(RenderScene, ThreadCentrelineLiesOnTheTrueProjectionWithDistortion) {
  // Cross-sections every 5 px: the peak fitted to the pixels within 3 px along the thread, and
  // their intensity centroid, against the true projection of the 3D centreline. A thread
  // thinner than a pixel along an image axis lights the same pixels wherever it passes within
  // (1 - w) / 2 of their centres (area sampling loses its position there), so the thin threads
  // are measured at the oblique angles.
  const calib::Camera distorted = DistortedCamera();
  const calib::Camera paper = calib::PaperRig(0.25).cameras[0];
  for (double width : {0.7, 3.0}) {
    std::vector<double> fitted, centroid;
    for (const ThreadCase& c : ThreadCases(distorted, paper)) {
      if (width < 1.0 && std::fmod(c.degrees, 90.0) == 0.0) continue;
      ForEachCrossSection(c, width, 5.0, [&](const cv::Mat& image, const LocalCurve& curve) {
        const std::vector<Sample> samples = SamplesNear(image, curve, 3.0);
        fitted.push_back(FitShift(samples, curve));
        double sum = 0.0, moment = 0.0;
        for (const Sample& s : samples) {
          sum += s.intensity;
          moment += s.intensity * s.across;
        }
        centroid.push_back(moment / sum);
      });
    }
    SCOPED_TRACE("width " + std::to_string(width));
    ASSERT_GT(fitted.size(), 500u);
    // Measured: fitted peak 0.0001 px RMS (w 0.7; largest 0.0004) and 0.0002 px RMS (w 3;
    // largest 0.0009); centroid 0.022 and 0.027 px RMS (its window's pixel selection is not
    // symmetric), mean within 0.002 px.
    EXPECT_LT(Rms(fitted), 0.05);
    EXPECT_LT(std::abs(Mean(fitted)), 0.01);
    EXPECT_LT(Rms(centroid), 0.05);
    EXPECT_LT(std::abs(Mean(centroid)), 0.01);
    std::printf(
        "width %.1f px: fitted peak %.4f px RMS (mean %+.4f, max %.4f), centroid %.4f px "
        "RMS (mean %+.4f), %zu cross-sections\n",
        width, Rms(fitted), Mean(fitted),
        std::abs(*std::max_element(fitted.begin(), fitted.end(),
                                   [](double x, double y) { return std::abs(x) < std::abs(y); })),
        Rms(centroid), Mean(centroid), fitted.size());
  }
}

TEST(RenderScene, EachRowAcrossAThinThreadSumsToItsArea) {
  // A thread steeper than 45 degrees crosses each row over w / cos(phi) px, phi its angle from
  // the vertical: the row's total intensity (area conservation).
  const calib::Camera camera = DistortedCamera();
  for (double degrees : {90.0, 73.0, 58.0, 104.0, 46.0}) {
    const double angle = degrees * std::numbers::pi / 180.0;
    const Eigen::Vector2d direction(std::cos(angle), std::sin(angle));
    const Eigen::Vector2d middle(117.4, 131.7);
    const Eigen::Vector3d a = Unproject(camera, middle - 140.0 * direction, 2.0);
    const Eigen::Vector3d b = Unproject(camera, middle + 140.0 * direction, 2.4);
    const double radius = 0.7 * 2.0 / (2.0 * camera.intrinsics.fx);  // w = 0.7 px at a
    const cv::Mat image = RenderScene(camera, ThreadScene(a, b, radius), SceneRenderOptions());
    std::vector<double> ratios;
    for (int y = 20; y < camera.intrinsics.height - 20; ++y) {
      // The true crossing of the row: bisection on the 3D line.
      double lo = 0.0, hi = 1.0;
      const bool down = camera.ProjectWorld(b).y() > camera.ProjectWorld(a).y();
      for (int i = 0; i < 60; ++i) {
        const double mid = 0.5 * (lo + hi);
        ((camera.ProjectWorld(a + mid * (b - a)).y() < y) == down ? lo : hi) = mid;
      }
      const LocalCurve curve = CurveAt(camera, a, b, lo, radius);
      if (curve.center.x() < 10 || curve.center.x() > camera.intrinsics.width - 11) continue;
      if (lo < 0.02 || lo > 0.98) continue;  // the row is beyond the thread's ends
      const double expected = curve.width / std::abs(curve.tangent.y());
      double sum = 0.0;
      for (int x = 0; x < camera.intrinsics.width; ++x) sum += Green(image, x, y);
      ratios.push_back(sum / expected);
    }
    ASSERT_GT(ratios.size(), 100u);
    SCOPED_TRACE("angle " + std::to_string(degrees));
    // Measured: every row within 0.01 % at each angle (the square pixel footprint makes each
    // pixel hold the thread's area in it, so a row holds its area in the row).
    double worst = 0.0;
    for (double r : ratios) worst = std::max(worst, std::abs(r - 1.0));
    EXPECT_NEAR(Mean(ratios), 1.0, 0.005);
    EXPECT_LT(worst, 0.03);
    std::printf("angle %5.1f: row sums / area: mean %.5f, worst %.5f\n", degrees, Mean(ratios),
                1.0 + worst);
  }
}

TEST(RenderScene, ThinThreadPeakIsItsAreaInThePixel) {
  // Along an image axis, through pixel centres: min(w, 1) on the centreline, the overlap of
  // [1 - w/2, 1 + w/2] with [-1/2, 1/2] one row off.
  calib::Camera camera = DistortedCamera();
  camera.intrinsics.distortion[0] = 0.0;
  camera.intrinsics.cx = camera.intrinsics.cy = 127.0;
  for (double w : {0.4, 0.7, 3.0}) {
    const double radius = w * 2.0 / (2.0 * camera.intrinsics.fx);
    const cv::Mat image = RenderScene(camera,
                                      ThreadScene(Unproject(camera, {20.0, 100.0}, 2.0),
                                                  Unproject(camera, {230.0, 100.0}, 2.0), radius),
                                      SceneRenderOptions());
    EXPECT_NEAR(Green(image, 127, 100), std::min(w, 1.0), 1e-4) << "w " << w;
    EXPECT_NEAR(Green(image, 127, 99), std::max(0.0, std::min(1.0, 0.5 * w - 0.5)), 1e-4);
  }
  // At 45 degrees through a pixel centre: the strip |x - y| <= w / sqrt(2) of the unit square
  // has area 1 - (1 - w / sqrt(2))^2 (0.745 for w = 0.7), with the square pixel footprint; the
  // interval footprint gives w.
  const double w = 0.7, radius = w * 2.0 / (2.0 * camera.intrinsics.fx);
  const Scene diagonal = ThreadScene(Unproject(camera, {27.0, 27.0}, 2.0),
                                     Unproject(camera, {227.0, 227.0}, 2.0), radius);
  SceneRenderOptions options;
  EXPECT_NEAR(Green(RenderScene(camera, diagonal, options), 127, 127),
              1.0 - std::pow(1.0 - w / std::sqrt(2.0), 2), 1e-4);
  options.square_pixel_footprint = false;
  EXPECT_NEAR(Green(RenderScene(camera, diagonal, options), 127, 127), w, 1e-4);
}

TEST(RenderScene, ThreadsAndBallsBehindTheCameraAreNotDrawn) {
  const calib::Camera camera = DistortedCamera();
  Scene scene = ThreadScene({0.1, 0.05, -1.0}, {0.1, 0.05, -3.0}, 0.01);
  scene.balls.push_back({{0.0, 0.0, -2.0}, 0.1, {1, 1, 1}});
  EXPECT_EQ(cv::countNonZero(RenderScene(camera, scene, SceneRenderOptions()).reshape(1)), 0);
  // A thread from behind the camera to in front of it: only the part in front is drawn, and
  // it ends where it leaves the image.
  const Eigen::Vector3d front = Unproject(camera, {60.0, 128.0}, 2.0);
  const cv::Mat image = RenderScene(camera, ThreadScene({front.x(), front.y(), -1.0}, front, 0.01),
                                    SceneRenderOptions());
  EXPECT_GT(Green(image, 60, 128), 0.99f);  // w = 3 px
  // A line parallel to the optical axis images as a ray from the principal point outwards; the
  // part behind the camera would appear on the other side.
  EXPECT_EQ(cv::sum(image(cv::Rect(140, 0, 116, 256)))[1], 0.0);
}

// Colour: a thick thread and a ball of known colour on black, exposed with each Bayer pattern
// and demosaiced, show that colour at their centre.
TEST(Expose, ColourOfAThickThreadSurvivesMosaicAndDemosaic) {
  const calib::Camera camera = DistortedCamera();
  const Colour colour(0.2f, 0.55f, 0.8f);  // BGR
  const cv::Vec3b expected(51, 140, 204);  // round(255 colour)
  Scene scene = ThreadScene(Unproject(camera, {30.0, 90.0}, 2.0),
                            Unproject(camera, {220.0, 110.0}, 2.0), 8.0 * 2.0 / (2.0 * 300.0),
                            colour);  // w = 8 px
  SceneRenderOptions options;
  options.ambient = 1.0;  // flat shading: the ball shows its colour
  scene.balls.push_back({Unproject(camera, {128.0, 200.0}, 1.5), 0.04, colour});  // r = 8 px
  const cv::Mat linear = RenderScene(camera, scene, options);
  const Eigen::Vector2d thread_center =
      camera.ProjectWorld(0.5 * (scene.threads[0].points[0] + scene.threads[0].points[1]));
  const cv::Point points[] = {{static_cast<int>(std::lround(thread_center.x())),
                               static_cast<int>(std::lround(thread_center.y()))},
                              {128, 200}};
  for (BayerPattern pattern : kAllPatterns)
    for (int depth : {8, 12}) {
      SCOPED_TRACE(BayerPatternName(pattern) + " " + std::to_string(depth) + " bit");
      SensorOptions sensor;
      sensor.bayer = pattern;
      sensor.bit_depth = depth;
      const cv::Mat raw = Expose(linear, camera.intrinsics, sensor);
      ASSERT_EQ(raw.type(), depth == 8 ? CV_8U : CV_16U);
      ColorCorrection correction;
      correction.bit_depth = depth;
      const cv::Mat bgr = Demosaic(raw, pattern, correction);
      for (const cv::Point& p : points)
        for (int c = 0; c < 3; ++c)
          EXPECT_NEAR(bgr.at<cv::Vec3b>(p)[c], expected[c], 2) << "channel " << c << " at " << p;
    }
}

TEST(Expose, MonoSensorRecordsLuminance) {
  const calib::Camera camera = DistortedCamera();
  cv::Mat linear(256, 256, CV_32FC3, cv::Scalar(0.2, 0.5, 0.8));
  SensorOptions sensor;
  sensor.bayer = BayerPattern::kNone;
  const cv::Mat raw = Expose(linear, camera.intrinsics, sensor);
  ASSERT_EQ(raw.type(), CV_8U);
  const double luminance = 0.0722 * 0.2 + 0.7152 * 0.5 + 0.2126 * 0.8;  // Rec. 709
  EXPECT_EQ(raw.at<uint8_t>(17, 33), std::lround(255 * luminance));
}

TEST(RenderScene, ThreadBehindABoxIsHiddenAndInFrontIsDrawn) {
  const calib::Camera camera = DistortedCamera();
  SceneRenderOptions options;
  options.ambient = 1.0;  // the box shows exactly its colour
  const Colour grey(0.5f, 0.5f, 0.5f), red(0.0f, 0.0f, 1.0f);
  Box box;
  box.center = Unproject(camera, {128.0, 128.0}, 3.0);
  box.half_extents = {0.3, 0.3, 0.1};  // ~60 px square
  box.orientation = Eigen::AngleAxisd(0.2, Eigen::Vector3d::UnitZ());
  box.colour = grey;
  for (double depth : {4.0, 2.0}) {
    SCOPED_TRACE("thread at depth " + std::to_string(depth));
    Scene scene = ThreadScene(Unproject(camera, {10.0, 128.0}, depth),
                              Unproject(camera, {246.0, 128.0}, depth), 4.0 * depth / 600.0,
                              red);  // 4 px wide
    scene.boxes.push_back(box);
    const cv::Mat image = RenderScene(camera, scene, options);
    // Inside the box's image, on the thread.
    const cv::Vec3f inside = image.at<cv::Vec3f>(128, 128);
    // Beside the box on the thread, and on the box beside the thread.
    EXPECT_NEAR(image.at<cv::Vec3f>(128, 20)[2], 1.0f, 1e-5);
    EXPECT_NEAR(image.at<cv::Vec3f>(100, 128)[0], 0.5f, 1e-5);
    if (depth > 3.0) {
      for (int c = 0; c < 3; ++c) EXPECT_NEAR(inside[c], grey[c], 1e-5);
    } else {
      for (int c = 0; c < 3; ++c) EXPECT_NEAR(inside[c], red[c], 1e-5);
    }
  }
}

TEST(RenderScene, DepthTestAgainstALargeTiltedBoxIsAccurateToMillimetres) {
  // A box face ~200 px across, turned 0.4 rad about the vertical so its depth changes by 0.25 m
  // across the image; a thread 5 mm in front of the face is drawn, 5 mm behind it is hidden
  // (its interior tiles are filled without ray casting, with depths interpolated).
  const calib::Camera camera = DistortedCamera();
  SceneRenderOptions options;
  options.ambient = 1.0;
  Box box;
  box.center = Unproject(camera, {128.0, 128.0}, 3.2);
  box.half_extents = {1.0, 1.0, 0.2};
  box.orientation = Eigen::AngleAxisd(0.4, Eigen::Vector3d::UnitY());
  box.colour = {0.5f, 0.5f, 0.5f};
  const Eigen::Vector3d toward_camera = box.orientation * Eigen::Vector3d(0.0, 0.0, -1.0);
  const Eigen::Vector3d face_center = box.center + 0.2 * toward_camera;
  const Eigen::Vector3d along = box.orientation * Eigen::Vector3d(1.0, 0.1, 0.0);
  for (double offset : {0.005, -0.005}) {
    SCOPED_TRACE("thread " + std::to_string(offset) + " m in front of the face");
    const Eigen::Vector3d a = face_center - 0.8 * along + offset * toward_camera;
    const Eigen::Vector3d b = face_center + 0.8 * along + offset * toward_camera;
    Scene scene = ThreadScene(a, b, 0.02, {0, 0, 1});  // ~4 px wide
    scene.boxes.push_back(box);
    const cv::Mat image = RenderScene(camera, scene, options);
    int checked = 0;
    for (double s = 0.05; s < 0.95; s += 0.05) {
      const Eigen::Vector2d pixel = camera.ProjectWorld(a + s * (b - a));
      const int x = static_cast<int>(std::lround(pixel.x()));
      const int y = static_cast<int>(std::lround(pixel.y()));
      const cv::Vec3f v = image.at<cv::Vec3f>(y, x);
      if (offset > 0) {
        EXPECT_NEAR(v[2], 1.0f, 1e-5) << "at " << pixel.transpose();
        EXPECT_NEAR(v[0], 0.0f, 1e-5) << "at " << pixel.transpose();
      } else {
        EXPECT_NEAR(v[2], 0.5f, 1e-5) << "at " << pixel.transpose();
      }
      ++checked;
    }
    EXPECT_EQ(checked, 18);
  }
}

TEST(RenderScene, BoxFacesFollowLambertShading) {
  const calib::Camera camera = DistortedCamera();
  SceneRenderOptions options;
  options.ambient = 0.25;
  options.light_direction = {0.0, 0.0, -1.0};  // from the camera (camera = world frame)
  Scene scene;
  Box box;
  box.center = {0.0, 0.0, 3.0};
  box.half_extents = {0.2, 0.2, 0.2};
  box.colour = {0.8f, 0.8f, 0.8f};
  box.orientation = Eigen::AngleAxisd(std::numbers::pi / 3.0, Eigen::Vector3d::UnitY());
  scene.boxes.push_back(box);
  const cv::Mat image = RenderScene(camera, scene, options);
  // Two faces are seen (+x and -z of the box), turned 30 and 60 degrees from the light:
  // 0.25 + 0.75 cos(angle).
  const Eigen::Vector2d left =
      camera.ProjectWorld(box.center + box.orientation * Eigen::Vector3d(0.2, 0.0, 0.0));
  const Eigen::Vector2d right =
      camera.ProjectWorld(box.center + box.orientation * Eigen::Vector3d(0.0, 0.0, -0.2));
  const float a = image.at<cv::Vec3f>(static_cast<int>(std::lround(left.y())),
                                      static_cast<int>(std::lround(left.x())))[1];
  const float b = image.at<cv::Vec3f>(static_cast<int>(std::lround(right.y())),
                                      static_cast<int>(std::lround(right.x())))[1];
  const double cos60 = 0.5, cos30 = std::sqrt(3.0) / 2.0;
  EXPECT_NEAR(std::max(a, b), 0.8 * (0.25 + 0.75 * cos30), 1e-5);
  EXPECT_NEAR(std::min(a, b), 0.8 * (0.25 + 0.75 * cos60), 1e-5);
}

TEST(RenderScene, BallIsCentredOnItsProjectedCentre) {
  const calib::Camera camera = DistortedCamera();
  SceneRenderOptions options;
  options.ambient = 1.0;  // flat: the centroid of its image is that of its outline
  for (const Eigen::Vector2d& pixel :
       {Eigen::Vector2d(128.3, 121.7), Eigen::Vector2d(101.55, 152.25),
        Eigen::Vector2d(170.8, 90.1)}) {
    Scene scene;
    scene.balls.push_back({Unproject(camera, pixel, 2.0), 0.03, {1, 1, 1}});  // r = 4.5 px
    const cv::Mat image = RenderScene(camera, scene, options);
    double sum = 0.0, sx = 0.0, sy = 0.0;
    for (int y = 0; y < image.rows; ++y)
      for (int x = 0; x < image.cols; ++x) {
        const double v = Green(image, x, y);
        sum += v;
        sx += v * x;
        sy += v * y;
      }
    const Eigen::Vector2d centroid(sx / sum, sy / sum);
    std::printf("ball at (%.2f, %.2f): centroid off by %.4f px, area / pi r^2 = %.4f\n", pixel.x(),
                pixel.y(), (centroid - camera.ProjectWorld(scene.balls[0].center)).norm(),
                sum / (std::numbers::pi * std::pow(0.03 * camera.intrinsics.fx / 2.0, 2)));
    // Measured: 0.014, 0.019, 0.027 px with the default 4 x 4 samples per pixel; 0.002, 0.003,
    // 0.009 px with 32 x 32 (what remains is real: off the axis, perspective and distortion
    // make the outline an ellipse whose centre is not quite the projected centre).
    EXPECT_LT((centroid - camera.ProjectWorld(scene.balls[0].center)).norm(), 0.05)
        << pixel.transpose() << " centroid " << centroid.transpose();
    // Area: pi r^2 with r the projected radius.
    const double r = 0.03 * camera.intrinsics.fx / 2.0;
    EXPECT_NEAR(sum, std::numbers::pi * r * r, 0.03 * std::numbers::pi * r * r);
  }
}

TEST(RenderScene, BallHidesTheThreadBehindIt) {
  const calib::Camera camera = DistortedCamera();
  SceneRenderOptions options;
  options.ambient = 1.0;
  Scene scene = ThreadScene(Unproject(camera, {10.0, 128.0}, 3.0),
                            Unproject(camera, {246.0, 128.0}, 3.0), 0.02, {0, 0, 1});
  scene.balls.push_back({Unproject(camera, {128.0, 128.0}, 2.0), 0.1, {0, 1, 0}});  // r 15 px
  const cv::Vec3f center = RenderScene(camera, scene, options).at<cv::Vec3f>(128, 128);
  EXPECT_NEAR(center[1], 1.0f, 1e-5);
  EXPECT_NEAR(center[2], 0.0f, 1e-5);
}

TEST(RenderScene, BackgroundFillsPixelsWithoutSolidsAndShowsThroughThinThreads) {
  const calib::Camera camera = DistortedCamera();
  calib::Camera straight = camera;
  straight.intrinsics.distortion[0] = 0.0;
  straight.intrinsics.cx = straight.intrinsics.cy = 127.0;
  Scene scene =
      ThreadScene(Unproject(straight, {10.0, 64.0}, 2.0), Unproject(straight, {246.0, 64.0}, 2.0),
                  0.5 * 2.0 / 600.0, {1, 1, 1});  // 0.5 px
  scene.background = {0.1f, 0.2f, 0.3f};
  const cv::Mat image = RenderScene(straight, scene, SceneRenderOptions());
  EXPECT_EQ(image.at<cv::Vec3f>(200, 200), scene.background);
  // Half covered: half thread, half background.
  const cv::Vec3f half = image.at<cv::Vec3f>(64, 128);
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(half[c], 0.5f + 0.5f * scene.background[c], 1e-4);
}

// Motion blur: renders with weights add up.
TEST(RenderScene, HalfWeightRendersSumToTheMeanImage) {
  const calib::Camera camera = calib::PaperRig(0.125).cameras[2];
  Scene a, b;
  for (Scene* s : {&a, &b}) {
    const double dx = s == &a ? 0.0 : 0.01;
    s->threads.push_back(
        {{{1.0 + dx, -0.3, -0.2}, {1.05 + dx, 0.3, 0.25}}, 0.002, {0.3f, 0.6f, 0.9f}});
    s->balls.push_back({{1.0 + dx, 0.0, 0.0}, 0.02, {0.9f, 0.9f, 0.9f}});
    s->boxes.push_back(
        {{2.2, 0.0, 0.0}, Eigen::Quaterniond::Identity(), {0.2, 0.15, 0.15}, {0.4f, 0.4f, 0.5f}});
    s->background = {0.05f, 0.05f, 0.05f};
  }
  const SceneRenderOptions options;
  cv::Mat blurred;
  RenderScene(camera, a, options, 0.5f, &blurred);
  RenderScene(camera, b, options, 0.5f, &blurred);
  const cv::Mat mean = 0.5 * (RenderScene(camera, a, options) + RenderScene(camera, b, options));
  EXPECT_LT(cv::norm(blurred, mean, cv::NORM_INF), 1e-6);
  EXPECT_GT(
      cv::norm(RenderScene(camera, a, options), RenderScene(camera, b, options), cv::NORM_INF),
      0.2);  // the two positions differ
}

TEST(RenderScene, RejectsBadAccumulatorsOptionsAndScenes) {
  const calib::Camera camera = DistortedCamera();
  const Scene scene;
  SceneRenderOptions options;
  cv::Mat wrong(10, 10, CV_32FC3);
  EXPECT_THROW(RenderScene(camera, scene, options, 1.0f, &wrong), std::invalid_argument);
  cv::Mat wrong_type(256, 256, CV_8UC3);
  EXPECT_THROW(RenderScene(camera, scene, options, 1.0f, &wrong_type), std::invalid_argument);
  EXPECT_THROW(RenderScene(camera, scene, options, 1.0f, nullptr), std::invalid_argument);
  options.max_piece_px = 0.0;
  std::string error;
  EXPECT_FALSE(options.IsValid(&error));
  EXPECT_NE(error.find("max_piece_px"), std::string::npos);
  EXPECT_THROW(RenderScene(camera, scene, options), std::invalid_argument);
  Scene bad = ThreadScene({0, 0, 1}, {NAN, 0, 1}, 0.001);
  try {
    RenderScene(camera, bad, SceneRenderOptions());
    ADD_FAILURE() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("thread 0 point 1"), std::string::npos) << e.what();
  }
}

TEST(Expose, NoiseHasTheRequestedStandardDeviation) {
  const calib::Camera camera = DistortedCamera();
  const cv::Mat flat(256, 256, CV_32FC3, cv::Scalar::all(0.5));
  for (int depth : {8, 12}) {
    SensorOptions sensor;
    sensor.bit_depth = depth;
    sensor.noise_sigma = 2.0;
    sensor.seed = 42;
    const cv::Mat raw = Expose(flat, camera.intrinsics, sensor);
    cv::Scalar mean, stddev;
    cv::meanStdDev(raw, mean, stddev);
    const double scale = sensor.white() / 255.0;
    SCOPED_TRACE(std::to_string(depth) + " bit");
    // Rounding adds 1/12 grey level^2 of variance: sqrt(4 + 1/12) = 2.02 at 8 bits. Measured:
    // 2.026 (8 bit) and 32.19 of 32.12 (12 bit).
    EXPECT_NEAR(stddev[0], 2.0 * scale, 0.05 * 2.0 * scale);
    std::printf("%d bit: noise %.3f (expected %.3f), mean %.3f (expected %.3f)\n", depth, stddev[0],
                2.0 * scale, mean[0], 0.5 * sensor.white());
    EXPECT_NEAR(mean[0], 0.5 * sensor.white(), 0.05 * scale);
    // Another seed gives other noise; the same seed the same.
    EXPECT_EQ(cv::norm(raw, Expose(flat, camera.intrinsics, sensor), cv::NORM_INF), 0.0);
    sensor.seed = 43;
    EXPECT_GT(cv::norm(raw, Expose(flat, camera.intrinsics, sensor), cv::NORM_INF), 0.0);
  }
}

TEST(Expose, VignettingFollowsTheCos4Law) {
  const calib::Camera camera = DistortedCamera();
  const cv::Mat flat(256, 256, CV_32FC3, cv::Scalar::all(0.8));
  for (double v : {1.0, 0.5}) {
    SensorOptions sensor;
    sensor.bit_depth = 16;
    sensor.vignetting = v;
    const cv::Mat raw = Expose(flat, camera.intrinsics, sensor);
    const double white = sensor.white();
    for (const cv::Point& p : {cv::Point(0, 0), cv::Point(255, 255), cv::Point(255, 0),
                               cv::Point(129, 127), cv::Point(60, 200)}) {
      const double tan2 = std::pow((p.x - camera.intrinsics.cx) / camera.intrinsics.fx, 2) +
                          std::pow((p.y - camera.intrinsics.cy) / camera.intrinsics.fy, 2);
      const double cos4 = 1.0 / ((1.0 + tan2) * (1.0 + tan2));
      EXPECT_NEAR(raw.at<uint16_t>(p), 0.8 * white * (1.0 - v * (1.0 - cos4)), 0.6)
          << "v " << v << " at " << p;
    }
    // The corner is darker than the centre by the cos^4 amount (here 0.79 for v = 1).
    EXPECT_LT(raw.at<uint16_t>(0, 0), 0.9 * raw.at<uint16_t>(127, 129));
  }
}

TEST(Expose, BlackLevelAndClamping) {
  calib::CameraIntrinsics k = DistortedCamera().intrinsics;
  k.width = 4;
  k.height = 2;
  cv::Mat linear(2, 4, CV_32FC3);
  const float values[4] = {0.0f, 0.5f, 1.0f, 2.0f};
  for (int x = 0; x < 4; ++x) {
    linear.at<cv::Vec3f>(0, x) = cv::Vec3f::all(values[x]);
    linear.at<cv::Vec3f>(1, x) = cv::Vec3f::all(-0.2f);
  }
  SensorOptions sensor;
  sensor.bit_depth = 12;
  sensor.black_level = 64.0;
  const cv::Mat raw = Expose(linear, k, sensor);
  // raw = black + value (white - black), clamped to [0, white].
  EXPECT_EQ(raw.at<uint16_t>(0, 0), 64);
  EXPECT_EQ(raw.at<uint16_t>(0, 1), 2080);  // 64 + 0.5 * 4031 = 2079.5, rounded half up
  EXPECT_EQ(raw.at<uint16_t>(0, 2), 4095);
  EXPECT_EQ(raw.at<uint16_t>(0, 3), 4095);
  EXPECT_EQ(raw.at<uint16_t>(1, 0), 0);
  // Demosaic with the same black level gives the display value back: 0.3 -> 76.5.
  calib::CameraIntrinsics k8 = k;
  k8.width = k8.height = 8;
  ColorCorrection correction;
  correction.bit_depth = 12;
  correction.black_level = 64.0;
  const cv::Mat display =
      Demosaic(Expose(cv::Mat(8, 8, CV_32FC3, cv::Scalar::all(0.3)), k8, sensor),
               BayerPattern::kRGGB, correction);
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(display.at<cv::Vec3b>(4, 4)[c], 76.5, 0.6);
  // 8 bits clamp at 255.
  sensor.bit_depth = 8;
  sensor.black_level = 10.0;
  const cv::Mat raw8 = Expose(linear, k, sensor);
  EXPECT_EQ(raw8.at<uint8_t>(0, 0), 10);
  EXPECT_EQ(raw8.at<uint8_t>(0, 3), 255);
  EXPECT_EQ(raw8.at<uint8_t>(1, 0), 0);
}

TEST(Expose, RejectsBadOptionsAndImages) {
  const calib::CameraIntrinsics k = DistortedCamera().intrinsics;
  const cv::Mat linear(256, 256, CV_32FC3, cv::Scalar::all(0.5));
  SensorOptions sensor;
  sensor.bit_depth = 9;
  EXPECT_THROW(Expose(linear, k, sensor), std::invalid_argument);
  sensor = SensorOptions();
  sensor.black_level = 255.0;
  EXPECT_THROW(Expose(linear, k, sensor), std::invalid_argument);
  EXPECT_THROW(Expose(cv::Mat(256, 256, CV_8UC3), k, SensorOptions()), std::invalid_argument);
  EXPECT_THROW(Expose(cv::Mat(128, 256, CV_32FC3), k, SensorOptions()), std::invalid_argument);
  cv::Mat with_nan = linear.clone();
  with_nan.at<cv::Vec3f>(17, 40) = cv::Vec3f::all(NAN);
  try {
    Expose(with_nan, k, SensorOptions());
    ADD_FAILURE() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("(x 40, y 17)"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace netlab::recon
