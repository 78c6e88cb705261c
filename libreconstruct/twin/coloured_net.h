#pragma once
// Synthetic ground truth for knot identity by colour (tests and benchmarks): a flat net of
// coloured links facing one camera, rendered by the twin's renderer, with the codebook of its
// knots and the knots as the camera sees them.

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "calibration/camera.h"
#include "libreconstruct/coloring/color_identify.h"
#include "libreconstruct/twin/render.h"

namespace netlab::recon {

// A flat square net of coloured links facing a camera, with its codebook.
struct ColouredNet {
  Scene scene;                               // straight threads, no knot balls (bare crossings)
  KnotCodebook codebook;                     // knot k = row * knots_per_side + col
  std::vector<Eigen::Vector3d> knot_points;  // world, m
  // Neighbouring knots of each knot in cyclic order around it (+col, +row, -col, -row).
  std::vector<std::vector<int>> neighbours;
};

// knots_per_side^2 knots `mesh_m` apart in a plane perpendicular to the camera's optical axis,
// centred `distance_m` in front of it, turned by `roll_rad` about the optical axis (threads along
// the image axes run along the rows of a Bayer mosaic: see IdentifyOptions::bayer); threads of
// `thread_radius_m`; each link one colour of
// `palette`, drawn at random (seed) until every knot's code is unique under CodeRule::kSet.
// Throws std::runtime_error when no such colouring is found in 10000 draws.
ColouredNet MakeColouredNet(const calib::Camera& camera, int knots_per_side, double mesh_m,
                            double distance_m, double roll_rad, double thread_radius_m,
                            const std::vector<PaletteColour>& palette, const Colour& background,
                            uint64_t seed);

// A knot as one camera sees it: its true pixel and the image directions of its yarns (unit, in
// the cyclic order of ColouredNet::neighbours), from projecting points 1 cm along each link.
struct KnotView {
  int knot = -1;
  Eigen::Vector2d pixel = Eigen::Vector2d::Zero();
  std::vector<Eigen::Vector2d> directions;
};
// The knots of `net` whose pixel lies at least `border_px` inside the image.
std::vector<KnotView> VisibleKnots(const calib::Camera& camera, const ColouredNet& net,
                                   double border_px);

}  // namespace netlab::recon
