#pragma once
// What the flight's acquisition adds to the twin's shots (docs/render.md, "Flight effects"):
// the lamps' flicker, the lens's depth of field, the cameras' differing responses, a textile
// background and a moving rig. Each is off by default (its `enabled()` false), and a shot
// without any is byte for byte the plain one.
//
//   Flicker flicker{100.0, 0.3};                     // 100 Hz ripple, 30 % depth
//   double gain = flicker.MeanOverExposure(t, 1e-3); // the frame's light, mean 1 over time
//   DepthOfField dof{4.0, 3.0, 5.5e-6};              // f/4 focused at 3 m
//   cv::Mat sharp_to_blurred = ApplyDepthOfField(linear, depth, camera.intrinsics.fx, dof);

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "calibration/rig.h"
#include "libreconstruct/twin/render.h"

namespace netlab::recon {

// The light's intensity over time, mean 1 over a period. Ripple (duty 0):
//   I(t) = 1 + depth cos(2 pi hz t)
// (the fundamental of a lamp on rectified mains: hz = 100 or 120; depth = (max - min) /
// (max + min), the "percent flicker"). PWM (0 < duty < 1): on during the first `duty` of every
// period, the off level 1 - depth of the on level, scaled so the mean is 1.
struct Flicker {
  double hz = 0.0;     // 0: steady light
  double depth = 0.0;  // in [0, 1]
  double duty = 0.0;   // 0: ripple; in (0, 1): PWM

  bool enabled() const { return hz > 0.0 && depth > 0.0; }
  // I(t), t in seconds of the simulation's clock (phase 0 at t = 0).
  double Intensity(double t) const;
  // The mean of I over [t - exposure / 2, t + exposure / 2] (I(t) when exposure is 0). Ripple:
  //   1 + depth cos(2 pi hz t) sin(pi hz exposure) / (pi hz exposure).
  double MeanOverExposure(double t, double exposure) const;
  // True when in range; else false with the reason.
  bool IsValid(std::string* error) const;
};

// The thin-lens blur. A point at depth d (camera z, m) seen through a lens of focal length f
// at f-number N focused at s spreads into a disc of diameter (on the sensor)
//   c = A |d - s| / d * f / (s - f),  A = f / N,
// in pixels c / pitch = fx (f / N) |d - s| / (d (s - f)) with f = fx pitch.
struct DepthOfField {
  double f_number = 0.0;          // 0: a pinhole (no blur)
  double focus_distance_m = 0.0;  // s, m
  double pixel_pitch_m = 5.5e-6;  // of the image (the paper's sensor: 5.5 um / --scale)

  bool enabled() const { return f_number > 0.0; }
  // The blur circle's diameter, px, of a point at depth `depth_m` (infinity: the background)
  // for a camera of focal length fx px.
  double CirclePx(double fx, double depth_m) const;
  bool IsValid(std::string* error) const;
};

// The linear image (CV_32FC3) seen through the thin lens: each pixel's light spread evenly
// over the disc of its depth's blur circle (`depth`: CV_32F camera z, m, +inf where only the
// background is seen), the disc's area in each pixel from 8 x 8 samples. Light is conserved.
cv::Mat ApplyDepthOfField(const cv::Mat& linear_bgr, const cv::Mat& depth, double fx,
                          const DepthOfField& dof);

// `cameras` responses drawn with `seed` at relative spread `sigma` (>= 0): white balance gains
// and the gain exp(N(0, sigma)), gamma exp(N(0, sigma / 2)), pixel gain non-uniformity sigma / 10,
// dark offsets sigma * 10 grey levels, hot pixels sigma / 1000 of the pixels.
std::vector<CameraResponse> DrawCameraResponses(int cameras, double sigma, uint64_t seed);

// The responses of a --camera-response file: a map `cameras:` of camera name to
// {white_balance: [R, G, B], gain, gamma, prnu, dsnu, hot_pixels, seed} (each optional; cameras
// not named keep the identity response). InputError naming the file, key and value.
std::vector<CameraResponse> ReadCameraResponses(const std::string& path, const calib::Rig& rig);

// A camera's pose moving during the shot: its centre displaced along `direction` (world, unit)
// by amplitude sin(2 pi hz t + phase) (a vibration), or, with hz 0, by amplitude from
// `step_time` on (a jump); the orientation is kept.
struct CameraMotion {
  double amplitude_m = 0.0;  // 0: still
  double hz = 0.0;           // 0: a step
  Eigen::Vector3d direction = Eigen::Vector3d::UnitX();
  double phase = 0.0;      // rad
  double step_time = 0.0;  // s

  bool enabled() const { return amplitude_m > 0.0; }
  // The displacement of the centre at time t, world, m.
  Eigen::Vector3d Displacement(double t) const;
  // The camera at time t.
  calib::Camera At(const calib::Camera& camera, double t) const;
};

// Fills amplitude and hz of a motion with a seeded direction and phase (camera c of the rig).
CameraMotion DrawCameraMotion(double amplitude_m, double hz, double step_time, uint64_t seed,
                              int c);

// The lamps of a shot (SceneRenderOptions::lamps and its shading constants).
struct LampRig {
  std::vector<Lamp> lamps;  // empty: the directional light
  double ambient = 0.15;    // of a surface's colour seen without a lamp
  double glossy = 0.0;      // the target's specular weight (0: matte)
  double shininess = 60.0;  // its Blinn-Phong exponent

  bool enabled() const { return !lamps.empty(); }
};

// The paper's four lamps as an example: one beside each camera of `rig` (15 cm outboard of it,
// across the flight axis, at its height), of equal power such that the lamps together light a
// face turned to each at `aim` to 1 - ambient (the scene's white); the target glossy (0.25).
LampRig PaperLamps(const calib::Rig& rig, const Eigen::Vector3d& aim);

// A --lamps file: {ambient, glossy, shininess, lamps: [{position: [x, y, z], power}, ...]}
// (world, m). InputError naming the file and key.
LampRig ReadLamps(const std::string& path);

// The mean reflectance of the textile panel (black cloth), of the scene's white.
inline constexpr double kTextileAlbedo = 0.1;

// A textile panel as a camera sees it (CV_32FC3 of the camera's size, linear): cloth of
// reflectance `albedo` (scene white 1) lit from `light` (camera frame) with folds (a few long
// sinusoidal ridges at seeded angles, Lambert-shaded) and a plain weave (a 2-px check of +-8 %);
// with `clutter`, the rig's structure along the frame's edges (bright bars and bolts).
cv::Mat TextileBackground(const calib::CameraIntrinsics& intrinsics, double albedo, bool clutter,
                          uint64_t seed);

}  // namespace netlab::recon
