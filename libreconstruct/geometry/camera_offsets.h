#pragma once
// The cameras' own clocks: when each camera's frames were taken.
//
// Frame times. A recording's timestamps (one file per camera: frame number -> s) give every
// labeled frame a time: the mean over the cameras that have timestamps, with the spread (largest
// minus smallest) kept per frame. Checked: each camera's timestamps cover every labeled frame,
// never run backwards, and the cameras agree on each frame to within one frame period.
//
// Sub-frame offsets. A camera whose frame t is exposed at frame time t + d (d a fraction of a
// frame: a trigger delay, a different exposure start) sees every moving knot where it was d
// frames later. Its label of a knot is moved back to the frame time along the knot's own 2D track
// in that camera (LabelAtFrameTime: the quadratic through the labels of frames t-1, t, t+1, or the
// line through two of them). The offset d of each camera is estimated from that same motion
// (EstimateCameraOffsets): every knot-frame the other cameras triangulate is projected into the
// camera, and d is the value that brings the camera's moved labels onto those projections
// (Gauss-Newton on the reprojection residual against d, weighted by the projection's own
// uncertainty; the cameras in turn until the offsets settle). Its standard deviation is the
// larger of the residual scatter's and a jackknife's over ten groups of knots (a knot's label
// errors persist from frame to frame and do not average out over the frames); a calibration
// error, a near-constant image shift while the knots move one way, is not in it. The rig's first
// camera is the reference (d = 0); the others are relative to it. With too little motion across
// the image (a net at rest, a camera that sees it head-on) the offset is not determined: its
// standard deviation exceeds max_sigma_frames, or the motion (read at the labels' own times) is
// not well above the labels' scatter, and no value is given.

#include <Eigen/Core>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "calibration/rig.h"
#include "libreconstruct/geometry/bundle_adjust.h"
#include "libreconstruct/labels/label_set.h"

namespace netlab::recon {

struct FrameTimes {
  std::vector<double> time_s;        // [T] mean over the cameras with timestamps
  std::vector<double> spread_s;      // [T] largest minus smallest of those
  std::vector<std::string> cameras;  // the cameras whose timestamps were used
};

// The frame times of `frame_index` from per-camera timestamps (`timestamps[c]`: frame number ->
// s; an empty map: that camera has none). `where[c]` names the camera's file for messages.
// InputError when a camera with timestamps lacks a labeled frame, its times do not increase over
// the labeled frames, or two cameras differ on a frame by more than 1 / fps. No camera with
// timestamps: time = frame / fps and spread 0.
FrameTimes FrameTimesFromTimestamps(const std::vector<int>& frame_index, double fps,
                                    const std::vector<std::string>& cameras,
                                    const std::vector<std::map<int, double>>& timestamps,
                                    const std::vector<std::string>& where);

// Label (camera c of `labels`, row t, knot k) moved to the frame time for a camera `offset` frames
// late, from the camera's labels of the knot in the neighbouring frames (frame numbers t-1 and
// t+1, those `usable` accepts). False when neither neighbour is usable. `velocity` (px per
// frame, at the label's own time) is set when not null.
bool LabelAtFrameTime(const LabelSet& labels, int c, int t, int k, double offset,
                      const std::vector<uint8_t>& usable, Eigen::Vector2d* px,
                      Eigen::Vector2d* velocity = nullptr);

// Which labels a reconstruction with `options` uses: present, not projected, accepted (or any
// with use_unreviewed). [C][T*K] of labels.labels.
std::vector<std::vector<uint8_t>> UsableLabels(const LabelSet& labels,
                                               const SequenceOptions& options);

// The labels' camera of each rig camera (-1: the labels have none). InputError naming a camera
// of the labels the rig does not have.
std::vector<int> LabelCameraOfRigCamera(const calib::Rig& rig, const LabelSet& labels);

struct OffsetOptions {
  double max_sigma_frames = 0.05;  // an offset less certain than this is not determined
  int min_observations = 20;       // fewer views of moving knots: not determined
  // The knots' image motion (RMS, px per frame) must exceed this many times the residual
  // scatter: a velocity read off labels that barely move is their noise.
  double min_motion_scatters = 3.0;
  int max_sweeps = 8;
  double tolerance_frames = 1e-4;  // a sweep changing no offset more than this ends them
};

struct CameraOffset {
  std::string camera;
  bool determined = false;  // false: no value (offset_frames NaN; why says so)
  double offset_frames = 0.0;
  double sigma_frames = 0.0;  // standard deviation, frames (residual scatter or jackknife)
  int observations = 0;       // views of moving knots it rests on
  double motion_px = 0.0;     // their RMS image motion, px per frame
  std::string why;            // when not determined
};

struct OffsetEstimate {
  std::vector<CameraOffset> cameras;  // the rig's order; [0] the reference
  int sweeps = 0;
  // Per rig camera, the offsets to apply (0 where not determined).
  std::vector<double> Applicable() const;
};

// Every camera's offset against the rig's first, from the labels (the same labels the
// reconstruction with `options` would use; its outlier threshold gates the residuals).
// InputError when the labels use a camera the rig lacks.
OffsetEstimate EstimateCameraOffsets(const calib::Rig& rig, const LabelSet& labels,
                                     const SequenceOptions& options,
                                     const OffsetOptions& offset_options = {});

}  // namespace netlab::recon
