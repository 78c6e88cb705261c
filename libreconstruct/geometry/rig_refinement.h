#pragma once
// Adjustment of a rig's extrinsics over a sequence (Adjustment::kRig of bundle_adjust.h), from
// points triangulated with the calibrated rig. The cameras are bolted to one frame, so each
// keeps one pose for the whole sequence; the intrinsics stay fixed. The gauge is held explicitly:
// the reference camera (the rig's first) does not move, and the second camera keeps its distance
// from it (the scale), its centre moving on a sphere about the first.

#include <Eigen/Core>
#include <vector>

#include "calibration/rig.h"
#include "libreconstruct/geometry/bundle_adjust.h"
#include "libreconstruct/geometry/triangulation.h"

namespace netlab::recon {

// One triangulated point and every view of it: where the adjustment starts from.
struct RigPoint {
  Eigen::Vector3d position;               // m, world frame
  std::vector<Observation> observations;  // camera indices into the rig; outliers included
};

// Adjusts the poses of every camera but the first (the second's centre on its sphere) and the
// points together, in two stages: Huber-weighted (scale triangulation.huber_px) over every
// observation (a camera knocked out of place has all its observations rejected as outliers by
// the first triangulation, so inliers alone would never move it), a few iterations; then plain
// least squares over the observations within triangulation.outlier_threshold_px of that solution
// (Huber's linear region made the first stage converge only linearly: 50 iterations instead
// of 5).
//
// Fills result's rig_rms_before_px and rig_rms_after_px (RMS reprojection residual over the
// observations of the second stage, px), and per camera (0 for the reference) the change
// (rig_rotation_change_deg, rig_center_change_mm) and its standard deviation
// (rig_rotation_sigma_deg, rig_center_sigma_mm). The new poses replace *rig's only when every
// camera is determined to options.rig_max_center_sigma_mm and options.rig_max_rotation_sigma_deg
// (result->rig_adjusted); otherwise *rig is left as it was. Reports "rig stages" through
// options.progress; a cancel of its token throws Cancelled. Does nothing with fewer than two
// cameras or no points.
void RefineRig(const std::vector<RigPoint>& points, const SequenceOptions& options,
               const TriangulationOptions& triangulation, calib::Rig* rig, SequenceResult* result);

}  // namespace netlab::recon
