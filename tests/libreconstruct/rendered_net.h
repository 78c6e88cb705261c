#pragma once
// A small net rendered for the labeling tools' tests: 4 x 4 knots of 1 mm yarns 1.5 m in front
// of a 16 mm camera (links ~190 px long, ~2 px wide), six dyes on black.

#include <random>
#include <utility>
#include <vector>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "calibration/rig.h"
#include "libreconstruct/render.h"

namespace netlab::recon::testing {

inline constexpr int kRows = 4, kCols = 4;
inline constexpr double kMesh = 0.1;

// A 4 x 4 net of 1 mm yarns 1.5 m in front of a 16 mm camera (2909 px focal length): links
// ~190 px long and ~2 px wide, in six dye colours on black, turned and tilted so that yarns
// meet at other angles than 90 degrees.
struct NetImage {
  calib::Camera camera;
  std::vector<Eigen::Vector3d> knots;
  cv::Mat image;  // CV_8UC3

  Eigen::Vector2d Pixel(int r, int c) const { return camera.ProjectWorld(knots[r * kCols + c]); }
};

// `missing`: links (knot a, knot b) left out of the picture; `offset` and `spin_deg` move the net
// (a later frame).
inline NetImage RenderNet(double tilt_deg, double noise_grey, uint64_t seed,
                          const std::vector<std::pair<int, int>>& missing = {},
                          const Eigen::Vector3d& offset = Eigen::Vector3d::Zero(),
                          double spin_deg = 0.0) {
  NetImage net;
  net.camera = calib::LookAtCamera("cam", {-1.5, 0.0, 0.0}, {0.0, 0.0, 0.0}, 16.0, 5.5, 1024);
  const Eigen::Matrix3d turn =
      (Eigen::AngleAxisd(0.35, Eigen::Vector3d::UnitX()) *
       Eigen::AngleAxisd(tilt_deg * M_PI / 180, Eigen::Vector3d::UnitZ()))
          .toRotationMatrix();
  for (int r = 0; r < kRows; ++r)
    for (int c = 0; c < kCols; ++c)
      net.knots.push_back(offset + Eigen::AngleAxisd(spin_deg * M_PI / 180, Eigen::Vector3d::UnitX()) *
                                       (turn * Eigen::Vector3d(0.0, (c - 1.5) * kMesh,
                                                               (r - 1.5) * kMesh)));
  const Colour dyes[] = {{0.1f, 0.2f, 0.9f}, {0.1f, 0.8f, 0.2f}, {0.9f, 0.2f, 0.1f},
                         {0.1f, 0.8f, 0.8f}, {0.8f, 0.1f, 0.8f}, {0.9f, 0.9f, 0.9f}};
  Scene scene;
  int n = 0;
  auto link = [&](int a, int b) {
    for (const auto& m : missing)
      if (m == std::pair(a, b)) return;
    ThreadPolyline t;
    t.points = {net.knots[a], net.knots[b]};
    t.radius = 0.0005;
    t.colour = dyes[n++ % 6];
    scene.threads.push_back(t);
  };
  for (int r = 0; r < kRows; ++r)
    for (int c = 0; c < kCols; ++c) {
      if (c + 1 < kCols) link(r * kCols + c, r * kCols + c + 1);
      if (r + 1 < kRows) link(r * kCols + c, (r + 1) * kCols + c);
    }
  const cv::Mat linear = RenderScene(net.camera, scene, SceneRenderOptions{});
  cv::Mat noisy = linear * 255.0;
  if (noise_grey > 0) {
    cv::Mat noise(noisy.size(), noisy.type());
    cv::RNG rng(seed);
    rng.fill(noise, cv::RNG::NORMAL, 0.0, noise_grey);
    noisy += noise;
  }
  noisy.convertTo(net.image, CV_8UC3);
  return net;
}

}  // namespace netlab::recon::testing
