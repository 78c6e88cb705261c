#pragma once
// Cameras that moved during a shot. In a parabolic flight the rig shakes and a camera can shift
// on its mount; the calibration then places it where it no longer is, and its labels sit off
// where the other cameras put the knots: by the same amount for every knot when it turned, by
// the parallax of its move when it slid.
//
// Each frame, each camera: every knot it labels that two or more other cameras triangulate
// without an outlier between them (ProjectAgreeingViews) gives a residual, its label minus where
// the others put the knot. The camera's shift in that frame is the median residual (each axis),
// its standard deviation 1.25 x 1.4826 MAD / sqrt(n) (the median's efficiency on Gaussian
// noise). The camera's place at the start of the shot is the median of its shifts over the first
// frames (a tenth of them, at least 5): a calibration error, the same in every frame, is not a
// move. A camera moved in the frames whose shift departs from that place by more than
// `min_departure_px` and by more than `sigmas` standard deviations (of the frame's shift and of
// the start's), for at least `min_frames` frames in a row.
//
// A moved camera's labels also pull the points the others are checked against, so the cameras
// are judged in turn: the one departing farthest is named, its labels are taken out of the
// others' points, and the rest are judged again without it.

#include <Eigen/Core>
#include <string>
#include <utility>
#include <vector>

#include "calibration/rig.h"
#include "libreconstruct/geometry/bundle_adjust.h"
#include "libreconstruct/labels/label_set.h"

namespace netlab::recon {

struct CameraMotionOptions {
  double min_departure_px = 0.5;
  double sigmas = 5.0;
  int min_frames = 2;
  int min_knots = 5;  // a frame's shift needs this many knots
};

struct CameraMotion {
  std::string camera;
  // Per labeled frame: its frame number, the camera's shift (NaN where fewer than min_knots
  // knots give one), the shift's standard deviation and the knots it is over.
  std::vector<int> frame;
  std::vector<Eigen::Vector2d> shift_px;
  std::vector<double> sigma_px;
  std::vector<int> knots;
  Eigen::Vector2d start_px = Eigen::Vector2d::Zero();  // its place at the start
  double start_sigma_px = 0.0;
  bool measured = false;  // a place at the start was found
  // Where it moved: runs of frame numbers [first, last], and its largest departure there.
  std::vector<std::pair<int, int>> moved;
  double largest_departure_px = 0.0;
  int largest_departure_frame = -1;
  std::string why;  // when not measured
};

// One entry per rig camera, in the rig's order. Every label but the projected ones is used,
// those under review too (a moved camera's labels go to review); options give the triangulation's
// outlier threshold.
std::vector<CameraMotion> DetectCameraMotion(const calib::Rig& rig, const LabelSet& labels,
                                             const SequenceOptions& options,
                                             const CameraMotionOptions& motion = {});

// "cam2 moved in frames 57-199: its labels up to 1.42 px (frame 120) from where it was at the
// start, against the other cameras' points", one sentence per moved camera.
std::vector<std::string> CameraMotionSentences(const std::vector<CameraMotion>& cameras);

}  // namespace netlab::recon
