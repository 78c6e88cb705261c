#include "libreconstruct/twin/coloured_net.h"

#include <cmath>
#include <random>
#include <stdexcept>

namespace netlab::recon {

ColouredNet MakeColouredNet(const calib::Camera& camera, int knots_per_side, double mesh_m,
                            double distance_m, double roll_rad, double thread_radius_m,
                            const std::vector<PaletteColour>& palette, const Colour& background,
                            uint64_t seed) {
  if (knots_per_side < 2 || palette.empty()) {
    throw std::invalid_argument("MakeColouredNet: need >= 2 knots per side and a palette");
  }
  const int n = knots_per_side;
  ColouredNet net;
  const Eigen::Vector3d axis = camera.ViewDirection();
  const Eigen::Vector3d centre = camera.Center() + distance_m * axis;
  // The camera's image x and y axes in the world: the net's columns and rows.
  const Eigen::Vector3d image_x =
      camera.cam_from_world.rotation.conjugate() * Eigen::Vector3d::UnitX();
  const Eigen::Vector3d image_y =
      camera.cam_from_world.rotation.conjugate() * Eigen::Vector3d::UnitY();
  const Eigen::Vector3d right = std::cos(roll_rad) * image_x + std::sin(roll_rad) * image_y;
  const Eigen::Vector3d down = -std::sin(roll_rad) * image_x + std::cos(roll_rad) * image_y;
  for (int r = 0; r < n; ++r) {
    for (int c = 0; c < n; ++c) {
      net.knot_points.push_back(centre + (c - 0.5 * (n - 1)) * mesh_m * right +
                                (r - 0.5 * (n - 1)) * mesh_m * down);
    }
  }
  // Links: (knot, knot) pairs; colour per link.
  std::vector<std::pair<int, int>> links;
  for (int r = 0; r < n; ++r) {
    for (int c = 0; c < n; ++c) {
      if (c + 1 < n) links.emplace_back(r * n + c, r * n + c + 1);
      if (r + 1 < n) links.emplace_back(r * n + c, (r + 1) * n + c);
    }
  }
  auto link_of = [&](int a, int b) {
    for (size_t l = 0; l < links.size(); ++l) {
      if ((links[l].first == a && links[l].second == b) ||
          (links[l].first == b && links[l].second == a)) {
        return static_cast<int>(l);
      }
    }
    return -1;
  };
  net.neighbours.resize(n * n);
  for (int r = 0; r < n; ++r) {
    for (int c = 0; c < n; ++c) {
      std::vector<int>& nb = net.neighbours[r * n + c];
      if (c + 1 < n) nb.push_back(r * n + c + 1);
      if (r + 1 < n) nb.push_back((r + 1) * n + c);
      if (c > 0) nb.push_back(r * n + c - 1);
      if (r > 0) nb.push_back((r - 1) * n + c);
    }
  }
  std::mt19937_64 rng(seed);
  std::uniform_int_distribution<int> pick(0, static_cast<int>(palette.size()) - 1);
  net.codebook.palette = palette;
  net.codebook.rule = CodeRule::kSet;
  std::vector<int> colour(links.size());
  for (int attempt = 0;; ++attempt) {
    if (attempt == 10000) {
      throw std::runtime_error("MakeColouredNet: no colouring with unique knot codes found");
    }
    for (int& c : colour) c = pick(rng);
    net.codebook.knots.clear();
    for (int k = 0; k < n * n; ++k) {
      CodebookKnot knot;
      knot.row = k / n;
      knot.col = k % n;
      for (int o : net.neighbours[k]) knot.link_colours.push_back(colour[link_of(k, o)]);
      net.codebook.knots.push_back(knot);
    }
    if (net.codebook.Collisions().empty()) break;
  }
  net.scene.background = background;
  for (size_t l = 0; l < links.size(); ++l) {
    ThreadPolyline thread;
    thread.points = {net.knot_points[links[l].first], net.knot_points[links[l].second]};
    thread.radius = thread_radius_m;
    thread.colour = palette[colour[l]].linear_bgr;
    net.scene.threads.push_back(thread);
  }
  return net;
}

std::vector<KnotView> VisibleKnots(const calib::Camera& camera, const ColouredNet& net,
                                   double border_px) {
  std::vector<KnotView> out;
  const int w = camera.intrinsics.width, h = camera.intrinsics.height;
  for (size_t k = 0; k < net.knot_points.size(); ++k) {
    KnotView view;
    view.knot = static_cast<int>(k);
    view.pixel = camera.ProjectWorld(net.knot_points[k]);
    if (!view.pixel.allFinite() || view.pixel.x() < border_px || view.pixel.y() < border_px ||
        view.pixel.x() > w - 1 - border_px || view.pixel.y() > h - 1 - border_px) {
      continue;
    }
    for (int o : net.neighbours[k]) {
      const Eigen::Vector3d towards =
          net.knot_points[k] + 0.01 * (net.knot_points[o] - net.knot_points[k]).normalized();
      view.directions.push_back((camera.ProjectWorld(towards) - view.pixel).normalized());
    }
    out.push_back(view);
  }
  return out;
}

}  // namespace netlab::recon
