#pragma once
// The renderer of the synthetic experiment: what a camera of the rig records of a simulated net
// (threads, knots, corner masses) and the target body. Two stages:
//
//   cv::Mat linear;                                   // CV_32FC3, linear light, BGR
//   for (int k = 0; k < 4; ++k)                       // motion blur: sub-frame renders
//     RenderScene(camera, SceneAt(t + k * dt / 4), options, 0.25f, &linear);
//   cv::Mat raw = Expose(linear, camera.intrinsics, sensor);   // CV_8U / CV_16U Bayer mosaic
//
// Rendering model (RenderScene), in the camera's full model (calibration/camera.h, Brown-Conrady
// distortion, OpenCV pixel convention: integer coordinates at pixel centres):
// - Solids (boxes, balls) are ray-cast through the undistorted ray of each sample into a colour,
//   coverage and depth buffer. Box pixels whose four corners see the same face take its (flat)
//   shade; the others, and every pixel of a ball, take solid_supersample^2 samples (area
//   sampling, so edges land with sub-pixel accuracy). Lambert shading:
//   colour * (ambient + (1 - ambient) max(0, n . light)), so a face turned to the light shows
//   exactly its colour. Pixels without a solid show the background.
// - Threads are chains of straight cylinders. Each piece is subdivided in 3D until its image is
//   at most max_piece_px long (distortion bends straight lines) and clipped at z = near_plane.
//   The image width of the thread is w = 2 radius fx / z, interpolated along the piece. A pixel
//   at distance d from the nearest point of the projected polyline (the minimum over its pieces,
//   so joins are not counted twice) is covered by the area of the strip [d - w/2, d + w/2]
//   across the nearest piece inside the square pixel: along the image axes, the overlap of
//   [d - w/2, d + w/2] with [-1/2, 1/2]; at other angles the pixel's footprint across the strip
//   is a trapezoid of width |cos| + |sin| (see square_pixel_footprint). The profile is symmetric
//   about the centreline, each row (or column) of pixels across the thread sums to the thread's
//   area in it, and a thin thread (w < 1) stays proportional to its area in the pixel (w along
//   the axes). The ends are round caps (w/2 beyond the end point).
// - Threads are composited "over" in depth order (the polylines sorted far to near by mean
//   depth) with their coverage as alpha. Where a solid is nearer than the thread, the thread
//   shows only through the part of the pixel the solid does not cover (none where it covers all).
//
// Cost: only pixels near each primitive are touched, in 32 x 32 tiles of a scratch canvas that
// each calling thread keeps between calls (48 bytes per pixel of the most tiles one render has
// touched: tens of MB for the benchmark's net at 2048 x 2048, at most 200 MB); the accumulator is
// touched once per call (only the touched tiles when the background is black). Tiles inside
// one face of a box are filled without ray casting (the face's image is convex).
// Each calling thread also caches the undistorted rays of the last few cameras it rendered (a
// grid of one ray every 8 pixels, interpolated bilinearly: < 0.01 px error for the paper's
// lenses). RenderScene is thread-safe: several threads may render different cameras at once.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "calibration/rig.h"
#include "libreconstruct/coloring/colour.h"
#include "libreconstruct/recording/bayer.h"

namespace netlab::recon {

// One yarn link: a chain of straight cylinders through `points` (world frame, m).
struct ThreadPolyline {
  std::vector<Eigen::Vector3d> points;
  double radius = 0.0005;  // m
  Colour colour{1, 1, 1};
};

// Knots and corner masses: shaded spheres.
struct Ball {
  Eigen::Vector3d center = Eigen::Vector3d::Zero();  // world, m
  double radius = 0.0;                               // m
  Colour colour{1, 1, 1};
};

// The target body: a shaded box.
struct Box {
  Eigen::Vector3d center = Eigen::Vector3d::Zero();                 // world, m
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();  // box axes to world
  Eigen::Vector3d half_extents = Eigen::Vector3d::Zero();           // along the box axes, m
  Colour colour{1, 1, 1};
};

struct Scene {
  std::vector<ThreadPolyline> threads;
  std::vector<Ball> balls;
  std::vector<Box> boxes;
  Colour background{0, 0, 0};  // where no solid is seen
};

// A point lamp: irradiance power / r^2 at distance r face-on, in units of the scene's white
// (power 1 lights a face 1 m away, turned to it, to exactly its colour above the ambient).
struct Lamp {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();  // world, m
  double power = 1.0;
};

struct SceneRenderOptions {
  // Towards the light (world, need not be unit length), for the Lambert shading of balls and
  // boxes. The default lights from above, behind the ejector and to the side.
  Eigen::Vector3d light_direction{-0.5, 0.3, 1.0};
  // Fraction of a solid's colour seen on its unlit side, in [0, 1].
  double ambient = 0.35;
  // Thread pieces are subdivided until each is at most this long in the image, px (> 0).
  double max_piece_px = 2.0;
  // Samples per pixel side for balls and at box edges (>= 1).
  int solid_supersample = 4;
  // Points nearer than this to the camera plane (camera z, m) are not drawn (> 0).
  double near_plane = 0.05;
  // The pixel a thread covers: true, the exact area of the (locally straight) thread in the
  // square pixel, so each row or column of pixels across a thread sums to its area there at any
  // angle; false, the interval [-1/2, 1/2] across the thread whatever its angle (the same along
  // the image axes; across a diagonal thin thread rows then sum to 0.85..1.1 of its area).
  bool square_pixel_footprint = true;
  // A background that varies per pixel (CV_32FC3 of the camera's size, linear), shown instead
  // of scene.background where no solid is seen; null: the uniform scene.background.
  const cv::Mat* background_image = nullptr;
  // Point lamps instead of light_direction (empty: the directional light). A point p of normal
  // n (balls, boxes) shows
  //   colour (ambient + sum_l power_l max(0, n . l) / r_l^2 [lamp l not hidden by a box])
  //   + glossy sum_l power_l max(0, n . h_l)^shininess / r_l^2 (boxes only, white),
  // l the unit vector to the lamp, r its distance, h the half vector of l and the view; a thread
  // of unit tangent t, a Lambertian cylinder, shows
  //   colour (ambient + sum_l power_l sqrt(1 - (t . l)^2) / r_l^2 [not hidden]),
  // taken at its points and interpolated along the pieces. Shadow rays are tested against the
  // scene's boxes (the target), so the target casts its shadow on the net and the knots.
  std::vector<Lamp> lamps;
  double glossy = 0.0;      // >= 0, the specular weight of boxes
  double shininess = 60.0;  // > 0, the Blinn-Phong exponent

  // True when every field is in range; else false with the reason in *error.
  bool IsValid(std::string* error) const;
};

// Adds weight * (the rendered linear image) to *accumulator: CV_32FC3 of the camera's size,
// created zeroed if empty. Motion blur = several calls with weights summing to 1. Throws
// std::invalid_argument on invalid options or camera intrinsics, a null accumulator, or one of
// the wrong type or size.
void RenderScene(const calib::Camera& camera, const Scene& scene, const SceneRenderOptions& options,
                 float weight, cv::Mat* accumulator);
// The same, also keeping in *depth (CV_32F of the camera's size, created +inf if empty) the
// least depth (camera z, m) of what each pixel sees: the nearest thread drawn there (not behind
// a solid covering the whole pixel) or solid; +inf where only the background is seen.
void RenderScene(const calib::Camera& camera, const Scene& scene, const SceneRenderOptions& options,
                 float weight, cv::Mat* accumulator, cv::Mat* depth);
// The rendered linear image (CV_32FC3, weight 1).
cv::Mat RenderScene(const calib::Camera& camera, const Scene& scene,
                    const SceneRenderOptions& options);

// How one camera's sensor and electronics differ from the ideal (the identity by default):
// a linear value v (after vignetting) at a site of colour c records as
//   (gain white_balance[c] (1 + prnu_xy) v)^gamma (white + black level + dsnu_xy + noise),
// prnu_xy ~ N(0, prnu) and dsnu_xy ~ N(0, dsnu grey levels of 8 bits) fixed per pixel (drawn
// with pattern_seed, the same every frame), and a hot_pixels fraction of the pixels reading
// white whatever the light. A mono sensor (kNone) takes the green gain.
struct CameraResponse {
  std::array<double, 3> white_balance{1.0, 1.0, 1.0};  // B, G, R gains
  double gain = 1.0;
  double gamma = 1.0;
  double prnu = 0.0;        // relative sigma of the pixels' gains
  double dsnu = 0.0;        // sigma of the pixels' dark offsets, grey levels of 8 bits
  double hot_pixels = 0.0;  // fraction of pixels, in [0, 1]
  uint64_t pattern_seed = 1;

  bool IsIdentity() const;
  bool IsValid(std::string* error) const;
};

struct SensorOptions {
  // The colour filter array; kNone: a mono sensor recording luminance (Rec. 709 weights on the
  // linear BGR image: 0.0722 B + 0.7152 G + 0.2126 R).
  BayerPattern bayer = BayerPattern::kRGGB;
  // 8 -> CV_8U; 10, 12, 16 -> CV_16U with values up to 2^bit_depth - 1.
  int bit_depth = 8;
  // Gaussian read noise, in grey levels of an 8-bit image (>= 0): sigma (white - black) / 255 in
  // output units, so it is `noise_sigma` again after Demosaic's colour correction.
  double noise_sigma = 0.0;
  // In [0, 1]. 0: none; 1: the full cos^4 law of the lens: gain = 1 - v (1 - cos^4 theta), with
  // tan theta the distance of the pixel from the principal point in normalised coordinates
  // ((u - cx) / fx, (v - cy) / fy).
  double vignetting = 0.0;
  // The raw value of black, in output units, in [0, 2^bit_depth - 1).
  double black_level = 0.0;
  // Noise seed (the caller passes one per camera and frame).
  uint64_t seed = 1;
  // The camera's response (identity: the ideal sensor above).
  CameraResponse response;

  // 2^bit_depth - 1: the raw value of linear 1.
  double white() const;
  // True when every field is in range; else false with the reason in *error.
  bool IsValid(std::string* error) const;
};

// The raw frame a sensor records of a linear BGR image (CV_32FC3, 1 = white): vignetting, the
// Bayer mosaic (each pixel keeps its site's colour, BayerColor), raw = black_level + value
// (white - black_level) + noise, rounded and clamped to [0, white]. Demosaic with
// ColorCorrection{bit_depth, black_level} maps it back to 8-bit display values (value * 255).
// Throws std::invalid_argument on invalid options, an image that is not CV_32FC3 or whose size
// differs from the intrinsics', or a non-finite value the sensor would record (naming where).
cv::Mat Expose(const cv::Mat& linear_bgr, const calib::CameraIntrinsics& intrinsics,
               const SensorOptions& options);

}  // namespace netlab::recon
