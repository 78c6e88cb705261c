#pragma once
// Visible knots with no label: where a camera has nothing of a knot that the others place.
//
// Knot k of frame row t is *missing* in camera c when c has neither a label of it nor a hidden
// mark (LabelState::kHidden), while two or more other cameras have accepted labels of it that
// triangulate consistently (TriangulatePoint; every view's reprojection residual within
// max_residual_px: an inconsistent pair never says where the knot should be) to a point in front
// of c whose projection lies inside c's image by margin_px (and is no artefact of the lens model
// folding a point far outside the field of view back into the image). Only the labels are used,
// never an image, and the target's shape is not known here: a knot the target hides from c is
// listed as well, until a person marks it hidden.
//
//   for (const MissingKnot& m : FindMissingKnots(labels, rig, rig_index, t))
//     MissingReason(m, labels.cameras);
//     // "no label; seen in cam0, cam2; expected near (812.4, 1033.0)"

#include <Eigen/Core>
#include <string>
#include <vector>

#include "calibration/rig.h"
#include "libreconstruct/labels/label_set.h"

namespace netlab::recon {

struct MissingKnotsOptions {
  // Each accepted view's reprojection residual at the triangulated point at most this (px): the
  // engine's epipolar tolerance (LabelEngineOptions::epipolar_tolerance_px).
  double max_residual_px = 2.0;
  // The expected point at least this far inside the image (px): a knot at the very edge cannot
  // be labeled there anyway (the detector's rings need ~20 px).
  double margin_px = 20.0;
  // Only where c has a label (any state) of one of the knot's grid neighbours. Off: a knot the
  // target hides is listed until a person marks it hidden (the workstation: D, or Shift+D
  // for the frames after it too), and so is every knot the labels expect. On: a knot none of whose neighbours c
  // has labeled (inside the target's shadow, or a patch c lost) is not listed until one is.
  // bench_missing on the demo shot: its labels.h5 lists 8 (all truly visible) off, 6 on; its
  // complete labels (labels_true.h5: every listed knot is behind the target) 1081 in 32 runs of
  // frames off, 502 in 18 on. Off by default: the list is there so that no visible knot goes
  // unasked.
  bool need_labeled_neighbour = false;

  // False with `why` when a value is out of range.
  bool IsValid(std::string* why) const;
};

struct MissingKnot {
  int camera = 0, t = 0, knot = 0;   // store camera, frame row, knot
  Eigen::Vector2d expected_px;       // where the other cameras put it in `camera` (px)
  std::vector<int> seen_in;          // the store cameras whose accepted labels place it
  double rms_px = 0.0;               // the triangulation's RMS residual (px)
};

// The missing knots of frame row t, in (camera, knot) order. `rig_index[c]`: the rig camera of
// store camera c. Reads only its arguments: any thread.
std::vector<MissingKnot> FindMissingKnots(const recon::LabelSet& labels, const calib::Rig& rig,
                                          const std::vector<int>& rig_index, int t,
                                          const MissingKnotsOptions& options = {});

// "no label; seen in cam0, cam2; expected near (812.4, 1033.0)".
std::string MissingReason(const MissingKnot& missing, const std::vector<std::string>& cameras);

}  // namespace netlab::recon
