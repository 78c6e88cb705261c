#pragma once
// Visible knots with no label: where a camera has nothing of a knot that it should see.
//
// Knot k of frame row t is *missing* in camera c when c has neither a label of it nor a hidden
// mark (LabelState::kHidden), and a point of the knot is known that lies in front of c, inside
// c's image (inside by margin_px, or beyond its outer edge by at most the point's error, see
// edge_sigmas; no artefact of the lens model folding a point far outside the field of view back
// into the image), and that the target does not hide from c (the segment from c's centre to the
// point passes through none of the target's solids). The point, first found first taken:
//   1. the other cameras' labels: two or more, accepted ones or, where those are too few, those
//      under review as well, that triangulate consistently (TriangulatePoint; every view's
//      reprojection residual within max_residual_px: an inconsistent pair never says where the
//      knot should be) and with a usable ray geometry (UsableGeometry, triangulation.h: two
//      cameras facing each other, with the knot near the line between them, have rays 0 deg
//      from head-on and place it nowhere);
//   2. its grid neighbours' points (as 1.): along each grid line through the knot, the midpoint
//      of the two neighbours, or the line carried on from two neighbours on one side; where
//      both grid lines give one, they must agree within neighbour_agreement of a link;
//   3. its own points (as 1.) in the frame rows around t: between the rows before and after, or
//      carried on from two rows on one side.
// Where one camera alone has a label of the knot (the others lost it, or the target hides it
// from them), the point of 2. or 3. is moved onto that label's ray when the ray passes within
// their tolerance (else the label is taken for a wrong one and 2. or 3. stands alone).
// Only the labels, the rig and the target are used, never an image. Without a target (no
// solids) a knot the target hides from c is listed as well, until a person marks it hidden.
//
//   MissingKnotsOptions options;
//   options.target = target;  // the target's solids in the rig's world frame, and the frame rate
//   for (const MissingKnot& m : FindMissingKnots(labels, rig, rig_index, t, options))
//     MissingReason(m, labels.cameras);
//     // "no label; seen in cam0, cam2; expected near (812.4, 1033.0)"

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <string>
#include <vector>

#include "calibration/rig.h"
#include "libreconstruct/geometry/triangulation.h"
#include "libreconstruct/labels/label_set.h"

namespace netlab::recon {

// One solid of the target (a box or a ball), moving at constant velocity: as a scenario's body
// (netsim::RigidBody) is at time s, centre + s * velocity.
struct TargetSolid {
  enum class Shape { kBox, kSphere };
  Shape shape = Shape::kBox;
  Eigen::Vector3d center = Eigen::Vector3d::Zero();                 // m, at time 0
  Eigen::Vector3d velocity = Eigen::Vector3d::Zero();               // m/s
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();  // box axes to world
  Eigen::Vector3d half_extents = Eigen::Vector3d::Zero();           // box, m
  double radius = 0.0;                                              // sphere, m
};

// The target as the cameras see it: its solids in the rig's world frame (the scenario's frame:
// a true rig, or one calibrated with the target's marker map), frame number f at time f / fps.
struct Target {
  std::vector<TargetSolid> solids;
  double fps = 179.0;
  bool empty() const { return solids.empty(); }
};

// Whether the segment from `from` to `to` passes through one of the target's solids at time
// `time_s` (s), each grown by `grow_m` (m; negative: shrunk).
bool TargetHides(const Target& target, const Eigen::Vector3d& from, const Eigen::Vector3d& to,
                 double time_s, double grow_m = 0.0);

// How far the image point q lies inside the outer edge of a width x height image (px; negative:
// outside, NaN: q is not finite): pixel centres at integers, the edge at -0.5 and size - 0.5, as
// `netlab render` counts a knot in view.
double InsideOuterEdgePx(const Eigen::Vector2d& q, int width, int height);
// The same along each axis: (inside the left/right edges, inside the top/bottom edges).
Eigen::Vector2d InsideOuterEdgeByAxisPx(const Eigen::Vector2d& q, int width, int height);

struct MissingKnotsOptions {
  // Each view's reprojection residual at the triangulated point at most this (px): the
  // engine's epipolar tolerance (LabelEngineOptions::epipolar_tolerance_px).
  double max_residual_px = 2.0;
  // The ray geometry: a point whose largest standard deviation for 1 px of label noise exceeds
  // this (mm) places nothing (UsableGeometry of triangulation.h, whose bound it is by default).
  double max_unit_sigma_mm = kMaxUnitSigmaM * 1e3;
  // The expected point at least this far inside the image (px), whose outer edge is at -0.5
  // and width - 0.5 (pixel centres at integers, as `netlab render` counts a knot in view).
  double margin_px = 0.0;
  // With margin_px 0, a point the cameras place (1.) is listed up to edge_sigmas standard
  // deviations of its projection beyond the outer edge (along each image axis, for label noise
  // of label_sigma_px per axis in each view, or the triangulation's RMS residual where larger),
  // and at most beyond_edge_px: a knot just inside the edge is expected up to its point's error
  // beyond it, and one whose point is further out than that is out of view, not missing. A
  // rough point (2., 3.), whose error is not known to the pixel, up to beyond_edge_px.
  // On the held-out shot's true labels (Net A 0.8 m/s, seed 5, 40 frames), the cameras place
  // 10 knots 0.03-1.0 px beyond the edge, which no camera sees; 3 of them lie within 3 sigma
  // (bench_missing --labels shot/labels_true.h5 --target shot/truth.h5, the row "the truth"
  // with the target: 5 false alarms, 3 placed by the cameras and 2 rough; 12 with 1 px for
  // every point).
  double label_sigma_px = 0.1;
  double edge_sigmas = 3.0;
  double beyond_edge_px = 1.0;
  // A point from the neighbours (2.): the two grid lines through the knot put it within this
  // fraction of their mean link length of each other, and one camera's ray passes within half
  // of it to be taken.
  double neighbour_agreement = 0.35;
  // A point from the knot's own motion (3.): from rows at most this far from t, trusted to
  // neighbour_agreement / 2 of its motion between them plus this (m).
  int motion_rows = 2;
  double motion_tolerance_m = 0.005;
  // The target: knots it hides are not missing. Empty: nothing is known to hide a knot.
  Target target;
  // The target's solids grown by this (m) for the test: a knot just beside its edge counts as
  // hidden (the knot's ball, the point's error).
  double target_grow_m = 0.0;
  // Only where c has a label (any state) of one of the knot's grid neighbours.
  bool need_labeled_neighbour = false;

  // False with `why` when a value is out of range.
  bool IsValid(std::string* why) const;
};

// Where the knot's point came from.
enum class MissingBasis { kCameras, kNeighbours, kMotion };

struct MissingKnot {
  int camera = 0, t = 0, knot = 0;  // store camera, frame row, knot
  Eigen::Vector2d expected_px;      // where the point projects in `camera` (px)
  MissingBasis basis = MissingBasis::kCameras;
  std::vector<int> seen_in;       // the store cameras whose labels place it (kNeighbours and
                                  // kMotion: the one whose ray it is on, or none)
  std::vector<int> under_review;  // of those, the ones whose label is under review
  std::vector<int> rows;          // kMotion: the frame rows whose points place it
  double rms_px = 0.0;            // kCameras: the triangulation's RMS residual (px)
};

// The missing knots of frame row t, in (camera, knot) order. `rig_index[c]`: the rig camera of
// store camera c. Reads only its arguments: any thread.
std::vector<MissingKnot> FindMissingKnots(const recon::LabelSet& labels, const calib::Rig& rig,
                                          const std::vector<int>& rig_index, int t,
                                          const MissingKnotsOptions& options = {});

// Why knot `knot` of frame row t is not missing in store camera `camera` (FindMissingKnots does
// not list it): "it has a label", "the target hides its point (no label; seen in cam0, cam2;
// expected near ...)", "its point projects to (2049.3, 611.0), outside the image", "no point: the
// labels in cam0, cam2 disagree (...)", ...; "" when it is missing.
std::string WhyNotMissing(const recon::LabelSet& labels, const calib::Rig& rig,
                          const std::vector<int>& rig_index, int camera, int t, int knot,
                          const MissingKnotsOptions& options = {});

// What the person reads, e.g. "no label; seen in cam0, cam2; expected near (812.4, 1033.0)",
// "no label; seen in cam0, cam2 (cam2 under review); expected near ...", "no label; seen in cam3,
// at the depth its grid neighbours give; expected near ...", "no label; its points in frames 11
// and 13 put it near ..." (frame numbers: `frame_index`, else frame rows).
std::string MissingReason(const MissingKnot& missing, const std::vector<std::string>& cameras,
                          const std::vector<int>& frame_index = {});

}  // namespace netlab::recon
