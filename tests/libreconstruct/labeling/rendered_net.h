#pragma once
// A small net rendered for the labeling tools' tests: 4 x 4 knots of 1 mm yarns 1.5 m in front
// of a 16 mm camera (links ~190 px long, ~2 px wide), six dyes on black. Optionally as the
// cameras of a shot see it (netlab render): grey knot balls, corner masses, a Bayer mosaic
// demosaiced bilinearly, farther away (thinner yarns).

#include <Eigen/Geometry>
#include <cmath>
#include <opencv2/core.hpp>
#include <random>
#include <utility>
#include <vector>

#include "calibration/rig.h"
#include "libreconstruct/recording/bayer.h"
#include "libreconstruct/twin/render.h"

namespace netlab::recon::testing {

inline constexpr int kRows = 4, kCols = 4;
inline constexpr double kMesh = 0.1;

// The six dyes of the plain renders (linear BGR).
inline std::vector<Colour> SixDyes() {
  return {{0.1f, 0.2f, 0.9f}, {0.1f, 0.8f, 0.2f}, {0.9f, 0.2f, 0.1f},
          {0.1f, 0.8f, 0.8f}, {0.8f, 0.1f, 0.8f}, {0.9f, 0.9f, 0.9f}};
}

// Net A's palette (coloring.yaml of the parabolic-flight nets) in linear BGR, as netlab render
// draws it: white, orange, lime, turquoise, royal blue, pink, brown. Royal blue and brown are
// a twentieth of white in some channels: the dim yarns.
inline std::vector<Colour> NetADyes() {
  auto linear = [](double srgb) {
    const double c = srgb / 255.0;
    return static_cast<float>(c <= 0.04045 ? c / 12.92 : std::pow((c + 0.055) / 1.055, 2.4));
  };
  const int srgb[7][3] = {{240, 240, 235}, {240, 120, 20},  {150, 200, 40}, {30, 180, 180},
                          {30, 60, 170},   {240, 120, 170}, {110, 70, 35}};
  std::vector<Colour> dyes;
  for (const auto& c : srgb) dyes.emplace_back(linear(c[2]), linear(c[1]), linear(c[0]));
  return dyes;
}

struct RenderNetOptions {
  double tilt_deg = 0.0;  // turn about the vertical, besides a fixed 20 degree roll
  // A turn of the net about its own normal first: with tilt_deg, its links meet at acute angles
  // in the image (a mesh seen sheared, as where a net folds).
  double in_plane_deg = 0.0;
  double noise_grey = 0.0;  // Gaussian noise, grey levels of the 8-bit image
  uint64_t seed = 1;
  std::vector<std::pair<int, int>> missing;  // links (knot a, knot b) left out of the picture
  Eigen::Vector3d offset = Eigen::Vector3d::Zero();    // moves the net (a later frame), m
  double spin_deg = 0.0;                               // turns it about the optical axis
  std::vector<std::pair<int, Eigen::Vector3d>> moved;  // single knots moved besides, m
  double distance_m = 1.5;               // camera to net centre: 1.5 m, yarns ~2 px; 3 m, ~1 px
  std::vector<Colour> dyes = SixDyes();  // cycled over the links
  std::vector<std::pair<int, int>> dim;  // links (knot a, knot b) dyed dim_factor as bright
  double dim_factor = 0.1;
  double knot_radius_m = 0.0;    // grey balls at the knots (netlab render: 1.5 yarn diameters)
  double corner_radius_m = 0.0;  // grey corner masses at the four corners
  bool bayer = false;            // an RGGB mosaic (sensor noise), demosaiced bilinearly
  // Buckled links (a slack knotless net): each link straight from its knots for bend_fraction of
  // its length, then shifted sideways by bend_m in the net's plane (all to one side: a sag).
  double bend_fraction = 0.0;
  double bend_m = 0.0;
  bool bend_alternate = false;  // every second link to the other side
};

// A 4 x 4 net of 1 mm yarns in front of a 16 mm camera (2909 px focal length), turned and
// tilted so that yarns meet at other angles than 90 degrees.
struct NetImage {
  calib::Camera camera;
  std::vector<Eigen::Vector3d> knots;
  cv::Mat image;  // CV_8UC3

  Eigen::Vector2d Pixel(int r, int c) const { return camera.ProjectWorld(knots[r * kCols + c]); }
};

inline NetImage RenderNet(const RenderNetOptions& o) {
  NetImage net;
  net.camera =
      calib::LookAtCamera("cam", {-o.distance_m, 0.0, 0.0}, {0.0, 0.0, 0.0}, 16.0, 5.5, 1024);
  const Eigen::Matrix3d turn =
      (Eigen::AngleAxisd(0.35, Eigen::Vector3d::UnitX()) *
       Eigen::AngleAxisd(o.tilt_deg * M_PI / 180, Eigen::Vector3d::UnitZ()))
          .toRotationMatrix() *
      Eigen::AngleAxisd(o.in_plane_deg * M_PI / 180, Eigen::Vector3d::UnitX()).toRotationMatrix();
  for (int r = 0; r < kRows; ++r)
    for (int c = 0; c < kCols; ++c)
      net.knots.push_back(o.offset +
                          Eigen::AngleAxisd(o.spin_deg * M_PI / 180, Eigen::Vector3d::UnitX()) *
                              (turn * Eigen::Vector3d(0.0, (c - 1.5) * kMesh, (r - 1.5) * kMesh)));
  for (const auto& [k, by] : o.moved) net.knots[k] += by;
  Scene scene;
  int n = 0;
  auto link = [&](int a, int b) {
    for (const auto& m : o.missing)
      if (m == std::pair(a, b)) return;
    ThreadPolyline t;
    t.points = {net.knots[a], net.knots[b]};
    if (o.bend_m > 0.0) {
      const Eigen::Vector3d along = net.knots[b] - net.knots[a];
      const Eigen::Vector3d side = (o.bend_alternate && n % 2 ? -1.0 : 1.0) *
                                   along.cross(turn * Eigen::Vector3d::UnitX()).normalized();
      t.points = {net.knots[a], net.knots[a] + o.bend_fraction * along + o.bend_m * side,
                  net.knots[b] - o.bend_fraction * along + o.bend_m * side, net.knots[b]};
    }
    t.radius = 0.0005;
    t.colour = o.dyes[n++ % o.dyes.size()];
    for (const auto& d : o.dim)
      if (d == std::pair(a, b)) t.colour *= static_cast<float>(o.dim_factor);
    scene.threads.push_back(t);
  };
  for (int r = 0; r < kRows; ++r)
    for (int c = 0; c < kCols; ++c) {
      if (c + 1 < kCols) link(r * kCols + c, r * kCols + c + 1);
      if (r + 1 < kRows) link(r * kCols + c, (r + 1) * kCols + c);
    }
  for (int k = 0; k < kRows * kCols; ++k) {
    const bool corner =
        k == 0 || k == kCols - 1 || k == (kRows - 1) * kCols || k == kRows * kCols - 1;
    if (corner && o.corner_radius_m > 0)
      scene.balls.push_back({net.knots[k], o.corner_radius_m, Colour(0.7f, 0.7f, 0.7f)});
    else if (o.knot_radius_m > 0)
      scene.balls.push_back({net.knots[k], o.knot_radius_m, Colour(0.5f, 0.5f, 0.5f)});
  }
  const cv::Mat linear = RenderScene(net.camera, scene, SceneRenderOptions{});
  if (o.bayer) {
    // netlab render's exposure: scene white at 0.85 of the sensor's.
    SensorOptions sensor;
    sensor.noise_sigma = o.noise_grey;
    sensor.seed = o.seed;
    const cv::Mat exposed = linear * 0.85;
    net.image = Demosaic(Expose(exposed, net.camera.intrinsics, sensor), BayerPattern::kRGGB,
                         ColorCorrection{});
    return net;
  }
  cv::Mat noisy = linear * 255.0;
  if (o.noise_grey > 0) {
    cv::Mat noise(noisy.size(), noisy.type());
    cv::RNG rng(o.seed);
    rng.fill(noise, cv::RNG::NORMAL, 0.0, o.noise_grey);
    noisy += noise;
  }
  noisy.convertTo(net.image, CV_8UC3);
  return net;
}

// The plain render of the first tests: `missing` links left out, `offset` and `spin_deg` move
// the net (a later frame).
inline NetImage RenderNet(double tilt_deg, double noise_grey, uint64_t seed,
                          const std::vector<std::pair<int, int>>& missing = {},
                          const Eigen::Vector3d& offset = Eigen::Vector3d::Zero(),
                          double spin_deg = 0.0) {
  RenderNetOptions o;
  o.tilt_deg = tilt_deg;
  o.noise_grey = noise_grey;
  o.seed = seed;
  o.missing = missing;
  o.offset = offset;
  o.spin_deg = spin_deg;
  return RenderNet(o);
}

}  // namespace netlab::recon::testing
