#pragma once
// The labeling engine: the automatic tools of netlab label and of the GUI, over a label store.
//
//   LabelEngine engine(&store, rig, images, options);   // images(camera, t): that frame, BGR
//   engine.LabelFrames(0, last);   // frame 0: Find Path from the four corners, then CrossCheck
//                                  // (epipolar consistency, Fill Grid); each later frame:
//                                  // Track from the one before, then CrossCheck
//   engine.FindNodeAt(camera, t, knot, centre, radius);  // the person's brush
//
// Every tool applies its labels as one undoable step of the store. A label is accepted only when
// its checks agree; otherwise it is kept for review with the reason (reasons(), per camera,
// frame and knot) — never guessed silently.
//
// A hidden mark (LabelState::kHidden: the person said the knot is not visible in that camera and
// frame) is the person's word: Find Path, Fill Grid and tracking never put a label over it; only
// the person's brush (FindNodeAt) does.
//
// Cross-camera checks (CrossCheck) need the rig, with the store's cameras in it:
//   * Epipolar consistency: every knot with accepted labels in two or more cameras is
//     triangulated (triangulation.h, consensus over pairs of views); a view it leaves out as an
//     outlier, or a point it cannot resolve, turns those labels to review.
//   * Fill Grid, repeated until nothing changes: a knot without an accepted label in a camera is
//     searched for there —
//       - where its triangulated point (from the cameras that have it) projects; found within
//         projection_tolerance_px and no other knot's projection near: accepted (two other
//         cameras vouch for it);
//       - else where spheres of link-length radius around its triangulated grid neighbours meet
//         (2 neighbours: a circle; 3 or more: the points on it at link length from the rest),
//         projected into the camera; the one unlabeled junction near that curve is a candidate;
//       - else (no neighbour seen by two cameras) at the image-space grid prediction from its
//         labeled neighbours in that camera (the midpoint of two opposite neighbours, or the
//         fourth corner of a parallelogram).
//     Candidates are accepted only when two or more cameras' candidates (or accepted labels)
//     triangulate consistently to a point at link length (within link_tolerance) from its
//     triangulated neighbours, and their yarns leave towards the knot's neighbours (as many as
//     its degree); otherwise they stay for review.
//     For a knotless net (edge_colour_step_px), an edge knot's junction must also lie where the
//     colour of its straight pair of links changes.
// Colour check (SetCodebook): a label whose yarn colours contradict its knot's is flagged.
// Without a rig (or with one camera) CrossCheck does the image-space part only, for review.

#include <Eigen/Core>
#include <array>
#include <functional>
#include <map>
#include <opencv2/core.hpp>
#include <optional>
#include <set>
#include <string>
#include <tuple>
#include <vector>

#include "calibration/rig.h"
#include "libreconstruct/geometry/point_motion.h"
#include "libreconstruct/geometry/triangulation.h"
#include "libreconstruct/labeling/knot_detect.h"
#include "libreconstruct/labeling/knot_track.h"
#include "libreconstruct/labeling/label_identity.h"
#include "libreconstruct/labeling/label_store.h"
#include "libreconstruct/labeling/missing_knots.h"

namespace netlab::recon {

struct LabelEngineOptions {
  KnotDetectorOptions detector;
  TrackOptions track;
  // Find Path in the first frame: an inner knot is accepted when its row and its column put it
  // within this distance.
  double row_column_agreement_px = 0.5;
  // Link length of the net (m, knot to knot); <= 0: estimated from the first frame's
  // triangulated neighbours (median).
  double link_length_m = 0.0;
  // A triangulated knot is consistent with its neighbours when its distance to each is at most
  // (1 + link_tolerance) link lengths and, for a taut pair, not much less (see .cc).
  double link_tolerance = 0.15;
  // Epipolar consistency: a view whose reprojection residual exceeds this is an outlier (px).
  double epipolar_tolerance_px = 2.0;
  // Fill Grid: a junction this close to a knot's projected point is that knot (px). And the
  // epipolar check flags a label of three views or more that the other views place farther
  // than this from the knot, beyond what label_sigma_px explains there.
  double projection_tolerance_px = 1.5;
  // ... and no other knot's label or projection may be within this (px).
  double exclusion_px = 6.0;
  // The labels' noise in each view, px per axis: above the tracked labels' own, for the rig's
  // error (docs/benchmarks.md, labeling, "The defaults").
  double label_sigma_px = 0.3;
  // Fill Grid: a junction is the knot only when its yarns leave towards the knot's neighbours
  // (each within this angle, deg) and their number is the knot's degree.
  double branch_tolerance_deg = 10.0;
  int fill_passes = 4;
  // Knotless nets (no knot ball: each link's dye ends at the junction): a junction Fill Grid or
  // Find Node finds for an edge knot, or tracking for an inner knot one yarn short, is doubted
  // where the colour of its straight pair of links changes farther than this from it (px,
  // Junction::colour_step; the engine asks its detectors for it). 0: off, for knotted nets,
  // whose knot ball moves the change 1-2.5 px.
  double edge_colour_step_px = 0.0;
  // Fill Grid, where no junction is found at a knot's projection (a folded net, a yarn beside
  // the knot's own, a dim dye): the projection itself is the label (LabelSource::kProjected)
  // when the labels of two or more other cameras, consistent, fix it there to place_sigma_px
  // (the projection's standard deviation along its worst axis for label_sigma_px of noise in
  // each view), the knot's yarns leave that place along at least two of its links, it lies on
  // the scene's own background (not on the target or another body, which could hide it), and
  // no other knot is within exclusion_px. Corners are left to their masses. 0: off. Why 0.5:
  // docs/benchmarks.md, labeling, "The defaults".
  double place_sigma_px = 0.5;
  // ... and where each of those views lies within this of their point (px).
  double place_residual_px = 0.5;
  // Where the other cameras' labels alone do not fix the knot (one camera sees it, or two whose
  // rays meet at a shallow angle), its motion may: a straight path at constant velocity fitted
  // to those views and to the knot's own labels (no placed ones) of every camera in up to
  // motion_frames frame rows before (else after; the adjacent one among them) (point_motion.h).
  // Each view must lie within place_residual_px of the path, and all together within chi^2's
  // 99.9 % for label_sigma_px per view; then place_sigma_px applies as above. 0: off.
  int motion_frames = 5;
  // ... and where no one of those views moves it by more than this (px in the camera placed):
  // the path fitted without each view in turn, where the rest still fix it, puts the knot
  // within this of where all of them do. A view whose small residual hides a large error (the
  // only view of a near camera, its label 1.7 px off) moves the place when left out.
  double place_leave_one_out_px = 1.0;
  // Fill Grid places it so only where, besides, the knot's label in the frame before moved as
  // its neighbours did to within this (px; the net moves nearly evenly over a mesh), or, where
  // they were not labeled then, its tracked label (the flow's end) is within this of the place.
  double place_motion_px = 1.5;
  // A knot the person placed by hand in the frame before (the engine had found no junction
  // there it could accept) is tracked onto a junction only within this of where the flow
  // carried the hand's label (px); farther, the junction is more likely a crossing beside the
  // knot than the knot, and the label is kept for review.
  double from_hand_snap_px = 1.0;
  // A knot is placed in a camera from the other cameras' labels only where one of those views
  // sees it at least 1 / place_max_magnification as finely (px per metre at the knot) as the
  // camera placed: the views' own errors grow by that ratio in it, and a tracked label's error
  // persists from frame to frame, so neither more views nor more frames of the coarse ones
  // average it away (in the wrapping, the near pair, 2.7 times finer than the far one, was given
  // places 2.0-3.7 px off from the far pair's labels).
  double place_max_magnification = 1.5;
  // The scene's background at a place: the median colour of the pixels within this of it
  // (and of the places this far to each side) differs from the whole frame's median by at
  // most background_tolerance (0..1 of the image's range).
  double background_reach_px = 10.0;
  double background_tolerance = 0.08;
  // The target's check (SetTarget): its solids shrunk by this (m), so that a knot on a face the
  // camera sees, its point a few millimetres off, is not taken for one behind it.
  double target_margin_m = 0.005;
  // A tool's label within this of the picture's outer edge (-0.5 .. size - 0.5) is kept for
  // review: the knot may lie just outside the picture, where a label inside it is still
  // tracked or placed from the part of the knot the picture holds (Net A at 1.0 m/s: a knot
  // 0.35 px beyond cam2's edge, tracked to a place inside it). 2 px covers the tools' labels'
  // own error (the largest measured in the wrapping, 1.7 px); 0: not checked.
  double picture_edge_px = 2.0;
  // Threads for the work that is independent per camera (tracking each camera's knots); the
  // labels do not depend on it.
  int threads = 2;
};

// Per camera, frame and knot: why a label needs review (absent: it does not, or there is none):
// ReviewReasons of libreconstruct/labels/label_set.h.

// The image positions of a knot's grid neighbours, slots right, down, left, up: `present` says
// which the net has, `px` which are known.
struct NeighbourSlots {
  std::array<bool, 4> present{false, false, false, false};
  std::array<std::optional<Eigen::Vector2d>, 4> px;
};

struct EngineCounts {
  int accepted = 0, review = 0;
};

// A knot's grid neighbours right, down, left, up in a rows x cols net (knot = row * cols + col);
// -1 where the net has none.
std::array<int, 4> GridSlots(int rows, int cols, int knot);

// The directions of a labeled knot's yarns for the colour check (CheckIdentity): its accepted
// grid neighbours' pixels in (camera, t), slots right, down, left, up (a doubtful neighbour would
// point the check at the wrong yarn).
YarnDirections AcceptedNeighbourYarns(const LabelSet& set, int camera, int t, int knot);

// What LabelFrames did: the labels each step set (accepted, kept for review), summed over the
// frames.
struct LabelingSummary {
  int frames = 0;              // frame rows labeled
  EngineCounts first_frame;    // Find Path in the first frame row
  EngineCounts tracked;        // Track into each later frame row
  EngineCounts cross_checked;  // CrossCheck of every frame row (review: also those it flagged)
};

class LabelEngine {
 public:
  // `images(camera, t)`: camera index of the store, frame row t; an empty Mat when unreadable.
  // The engine keeps the last few frames it asked for. `rig` may be null; otherwise it must
  // contain every camera of the store (by name).
  using ImageSource = std::function<cv::Mat(int camera, int t)>;
  LabelEngine(LabelStore* store, const calib::Rig* rig, ImageSource images,
              LabelEngineOptions options = {});

  // Find Path from the seeded corners of frame t in every camera that has four, or three (sides,
  // then rows and columns; inner knots where row and column agree). With three, the fourth
  // corner's two sides are found first where the grid of the other two sides puts them (a
  // corner behind the target). Returns the labels set.
  EngineCounts LabelFirstFrame(int t);
  // Find Path between accepted knots of frame row t, in every camera: each run of knots of a row
  // or a column without an accepted label between two accepted ones is followed along its yarn;
  // a knot found along both its row and its column, in agreement (row_column_agreement_px),
  // with its yarns towards its neighbours, is accepted; found along one of them only, it is
  // kept for review, a candidate the other cameras may confirm (CrossCheck). For the cameras
  // that see too few corners to start from (the near pair in the first frame: the net is
  // larger than their view), once Fill Grid has given them knots around the gaps.
  EngineCounts FillByPaths(int t);
  // FillByPaths(t), then CrossCheck(t) again where it accepted labels: what both set.
  EngineCounts FillByPathsAndCheck(int t);
  // Tracks every label of frame `from` into frame `to` (an adjacent frame) where `to` has none,
  // and where `to` has a label tracked from one under review that has since been accepted.
  EngineCounts Track(int from, int to);
  // Epipolar consistency and Fill Grid in frame t (see above); then the colour check, when set.
  EngineCounts CrossCheck(int t);
  // The automatic labeling of frame rows first to last (inclusive): LabelFirstFrame(first) and
  // CrossCheck(first) (and FillByPaths(first) with CrossCheck again where it accepted labels),
  // then for each later row t Track(t - 1, t) and CrossCheck(t).
  // `after_frame(t)`, when set, is called as soon as row t is done: a caller may report progress,
  // or edit row t (a person's corrections) before the next row is tracked from it.
  using FrameDone = std::function<void(int t)>;
  LabelingSummary LabelFrames(int first, int last, const FrameDone& after_frame = {});
  // Tracking from a labeled frame row `from` towards row `to`, forwards or backwards: each row t
  // after `from` is tracked from the row before it (in the run's direction), then cross-checked.
  // `checkpoint(t)`, when set, is called once row t is done; false stops the run there (the
  // person cancelled, or too much needs review). summary.frames counts the rows done.
  using Checkpoint = std::function<bool(int t)>;
  LabelingSummary TrackFrames(int from, int to, const Checkpoint& checkpoint = {});
  // Checks every accepted label of frame t that a tool found (Find Path, Fill Grid, tracking,
  // Find Node; not the person's own clicks, imported seeds, or labels placed where the other
  // cameras put the knot: their identity is those cameras' labels') against the yarn colours of
  // its knot (label_identity.h): a confident contradiction turns it to review with the colours
  // read; the label is never moved or renamed. Returns the labels flagged.
  int CheckColours(int t);
  // The net's colouring as the cameras see it; CrossCheck then ends with CheckColours.
  void SetCodebook(KnotCodebook codebook, IdentityCheckOptions options = {});
  // The target (missing_knots.h: its solids in the rig's world frame, frame number f at time
  // f / fps). CrossCheck then keeps for review a tool's label of a knot that the target hides
  // from its camera: where two or more other cameras' labels place the knot, consistently and
  // with a usable ray geometry, behind the target (its solids shrunk by target_margin_m). Empty
  // (the default): nothing is known to hide a knot.
  void SetTarget(Target target) { target_ = std::move(target); }
  // That check of frame row t alone; returns the labels turned to review.
  int CheckHidden(int t);
  // Keeps for review every tool's label of frame row t (not the person's clicks or imported
  // seeds) within picture_edge_px of its picture's outer edge; CrossCheck runs it first and
  // after Fill Grid. Returns the labels turned to review.
  int CheckPictureEdge(int t);
  // The person's brush: Find Node in (camera, t) at `centre`; a knot found is labeled `knot`,
  // accepted unless it contradicts what is known of that knot (then kept for review with the
  // reason): its yarns must run towards its accepted neighbours in that view, as in Fill Grid
  // but some may be hidden (two at least seen), when two or more links' directions are known;
  // and it must lie within projection_tolerance_px of where two or more other cameras' accepted
  // labels of the knot, consistent among themselves, put it (as Fill Grid's own projection), or
  // where fewer, with the knot's path (MotionPoint), put it to a pixel; and where one other
  // camera has a label of the knot, it must lie on that label's epipolar line. A junction is
  // accepted only where something confirms it is the knot and not a crossing of yarns: those
  // cameras, its motion since the adjacent frame as its neighbours moved, every link's
  // direction known and each of its yarns along one, or (a corner) its corner mass with the
  // corner's two yarns alone; otherwise it is kept for review. Where the brush finds no
  // junction and they fix the knot within the brush (OthersPlace), the label is placed there
  // (LabelSource::kProjected): the person's brush says the knot is seen. A junction they put
  // elsewhere is kept for review (one of the two is wrong, and nothing tells which); several
  // junctions, none where they put it, are left to the person. Returns the detector's result
  // (projected: placed from the other cameras).
  FindNodeResult FindNodeAt(int camera, int t, int knot, const Eigen::Vector2d& centre,
                            double radius_px);
  // The person's word on a knot in frame row t: `person` lists the cameras whose label of it the
  // person has just set (placed, moved, accepted, or found with the brush). The knot's other
  // accepted labels that a tool made (not the person's clicks or imported seeds, nor those
  // cameras) are checked against the views with the person's, as the epipolar check does: a
  // label that the other views place farther than projection_tolerance_px from the knot, beyond
  // what label_sigma_px explains there, turns to review; where the tools' labels agree with each
  // other and the person's one view is the odd one, all of them do (the person looked; nothing
  // tells which of the tools' labels misled the rest). Where two of the person's views disagree,
  // nothing is flagged: the person has said both. Tracking checked each label only against
  // the views of its own time: a label tracked 3.3 px off stayed accepted after the person had
  // set the knot's three other views. Returns the labels turned to review.
  int CheckAgainstPerson(int t, int knot, const std::vector<int>& person);

  // Where the accepted labels of two or more other cameras (not themselves projected) put a
  // knot in (camera, t), when they agree and fix it to place_sigma_px; else, with one view or
  // more, where they and the knot's path (MotionPoint) put it, when it fixes it to
  // place_sigma_px (*by_motion set); nullopt otherwise.
  std::optional<Eigen::Vector2d> OthersPlace(int camera, int t, int knot,
                                             bool* by_motion = nullptr) const;
  // The knot's point in frame row t from the other cameras' labels there and its own labels in
  // the adjacent frame rows, on a straight path at constant velocity (LabelEngineOptions::
  // motion_frames); nullopt where they do not fix it or do not fit such a path.
  std::optional<PointEstimate> MotionPoint(int camera, int t, int knot) const;
  // The knot's own labels (not placed ones) of every camera but `camera` (-1: of every camera)
  // in frame row t, as views of the rig; none without a rig.
  std::vector<Observation> OtherViews(int camera, int t, int knot) const;
  // Whether one of `views` sees `point` at least 1 / place_max_magnification as finely as
  // `camera` does (px per metre).
  bool FineEnough(int camera, const std::vector<Observation>& views,
                  const Eigen::Vector3d& point) const;
  const ReviewReasons& reasons() const { return reasons_; }
  double link_length_m() const { return link_length_m_; }
  // Takes `m` (> 0) as the net's link length when none is set or estimated yet: one another
  // engine estimated on a copy of the same labels (the GUI's Fill Grid preview), so that both
  // judge the next frames alike. Otherwise does nothing.
  void AdoptLinkLength(double m) {
    if (link_length_m_ <= 0.0 && m > 0.0) link_length_m_ = m;
  }
  // (camera, frame row, knot) of the labels Find Path found along their row or column alone:
  // Fill Grid takes them as candidates that other cameras may confirm.
  using KnotsInFrames = std::set<LabelAddress>;
  const KnotsInFrames& one_path() const { return one_path_; }
  // Takes those of another engine that ran on a copy of the same labels (the GUI's previews).
  void AdoptOnePath(const KnotsInFrames& more) { one_path_.insert(more.begin(), more.end()); }

 private:
  const cv::Mat& Image(int camera, int t);
  int RigIndex(int camera) const { return rig_index_[camera]; }
  void Note(int camera, int t, int knot, const std::string& why);
  // The label of (camera, t, knot) as it is, turned to review with `why`, appended to `flags`.
  void ToReview(int camera, int t, int knot, const std::string& why, std::vector<LabelEdit>* flags);
  EngineCounts Commit(const std::string& name, const std::vector<LabelEdit>& edits);
  // LabelFirstFrame with three corners seeded: Find Node on the knots of the fourth corner's
  // row and column (not the corner), where the homography of the other two sides' knots (`px`:
  // each knot's label so far) puts them; into *edits as accepted, for the branch check to judge.
  void FindFarSides(int camera, int t, const cv::Mat& image,
                    const std::function<std::optional<Eigen::Vector2d>(int)>& px,
                    std::vector<LabelEdit>* edits, std::map<int, Junction>* junction_of);
  // The median distance between neighbouring triangulated knots (every view an inlier), unless
  // the link length is set.
  void EstimateLinkLength(const std::vector<std::optional<Eigen::Vector3d>>& points);
  // GridSlots of the store's net.
  std::array<int, 4> SlotKnots(int knot) const;
  std::vector<int> Neighbours(int knot) const;  // those there are, in that order
  // Why a junction Find Node found for `knot` in (camera, t) is doubtful; empty when it is not.
  std::string FoundNodeDoubt(int camera, int t, int knot, const Junction& j) const;
  // How far `px` in (camera, t) is from where the knot's accepted label of an adjacent frame
  // row (t - 1, else t + 1) moved as its neighbours accepted in both rows did on average (px);
  // nullopt where there is no such label or fewer than two such neighbours.
  std::optional<double> MotionOff(int camera, int t, int knot, const Eigen::Vector2d& px) const;
  // Whether the path through `views` puts the knot at t in `camera` within
  // place_leave_one_out_px of `e`'s place however one view is left out (where the rest fix it).
  bool NoViewMovesIt(int camera, const std::vector<TimedObservation>& views, int t,
                     const PointEstimate& e) const;
  // How far `px` in (camera, t) is from where the knot's accepted labels in the two or three
  // frame rows before t (else after), at constant velocity, put it (px); nullopt where there are
  // fewer than two such labels.
  std::optional<double> VelocityOff(int camera, int t, int knot, const Eigen::Vector2d& px) const;
  // The smaller of MotionOff and VelocityOff, where either is known: how far px is from where
  // this camera's own labels say the knot moved (as its neighbours did, or as it was moving).
  std::optional<double> OwnMotionOff(int camera, int t, int knot, const Eigen::Vector2d& px) const;
  // Whether another knot's accepted label in (camera, t) is within exclusion_px of `px`.
  bool LabelNear(int camera, int t, int knot, const Eigen::Vector2d& px) const;
  // The image positions of a knot's neighbours in (camera, t), right, down, left, up: accepted
  // labels, else the projections of their triangulated points.
  NeighbourSlots Slots(int camera, int t, int knot,
                       const std::vector<std::optional<Eigen::Vector3d>>& point) const;

  // CrossCheck's steps (label_engine.cc). FrameCheck: the state of one frame row's check, shared
  // by its steps; FillView: one camera's frame in a Fill Grid pass; FillCandidate: a junction a
  // search found for a knot, to be confirmed by the other cameras.
  struct FrameCheck;
  struct FillView;
  struct FillCandidate;
  using FillCandidates = std::map<int, std::vector<FillCandidate>>;  // per knot
  // The accepted labels of every knot triangulated (FrameCheck::point, ::clean); with `flags`,
  // the views the triangulation leaves out, or of a point it cannot resolve, flagged for review.
  void TriangulateAccepted(FrameCheck* f, std::vector<LabelEdit>* flags);
  // Epipolar consistency: the flags committed, the points triangulated again without them, the
  // link length estimated. Returns the labels flagged.
  int CheckEpipolar(FrameCheck* f);
  // One pass of Fill Grid over every camera; its labels committed.
  EngineCounts FillGridPass(FrameCheck* f, int pass);
  // Fill Grid's searches in one camera for each knot without an accepted label there: an
  // accepted label (a) appended to `edits`, a candidate (b, c) to `candidates`.
  void SearchCamera(FrameCheck* f, int camera, std::vector<LabelEdit>* edits,
                    FillCandidates* candidates);
  // A knot Find Path found along its row or its column only, kept for review: its junction as
  // a candidate, where its yarns lead to its neighbours.
  std::optional<FillCandidate> PathCandidate(FrameCheck* f, const FillView& view, int knot);
  // (a) At the projection of the knot's triangulated point: an accepted label when found there,
  // else the projection itself where the other cameras fix it well and its yarns are there
  // (place_sigma_px).
  std::optional<LabelEdit> SearchAtProjection(FrameCheck* f, const FillView& view, int knot);
  std::optional<LabelEdit> PlaceAtProjection(FrameCheck* f, const FillView& view, int knot);
  // (b) The projected samples of the lens where spheres of link length around the knot's
  // triangulated neighbours meet (`how` says so); empty when they do not fix it.
  std::vector<Eigen::Vector2d> LinkSphereRegion(const FrameCheck& f, const FillView& view, int knot,
                                                std::string* how) const;
  // The one unlabeled junction near a region's samples, as a candidate.
  std::optional<FillCandidate> SearchRegion(FrameCheck* f, const FillView& view, int knot,
                                            std::vector<Eigen::Vector2d> region,
                                            const std::string& how);
  // (c) At the image-grid prediction from the knot's labeled neighbours in that camera.
  std::optional<FillCandidate> SearchImageGrid(FrameCheck* f, const FillView& view, int knot);
  // Whether another knot's accepted label or projection is within exclusion_px of `px`.
  bool TakenNear(const FrameCheck& f, int camera, int knot, const Eigen::Vector2d& px) const;
  // Candidates become labels, accepted where the cameras agree in 3D, else for review.
  void AcceptCandidates(const FrameCheck& f, const FillCandidates& candidates,
                        std::vector<LabelEdit>* edits);
  // A knot's candidates (with its accepted labels) triangulated: the inliers accepted (appended
  // to `edits`, true); false with `why` when they are not confirmed.
  bool ConfirmCandidates(const FrameCheck& f, int knot, const std::vector<FillCandidate>& list,
                         std::vector<LabelEdit>* edits, std::string* why) const;
  // One label per (camera, knot), and no accepted label within exclusion_px of another.
  std::vector<LabelEdit> OneLabelPerPlace(int t, const std::vector<LabelEdit>& edits);

  LabelStore* store_;
  const calib::Rig* rig_;
  ImageSource images_;
  LabelEngineOptions o_;
  std::vector<int> rig_index_;  // per store camera, its rig index (-1 without a rig)
  std::map<std::pair<int, int>, cv::Mat> cache_;
  ReviewReasons reasons_;
  KnotsInFrames one_path_;  // see one_path()
  double link_length_m_ = 0.0;
  std::optional<KnotCodebook> codebook_;
  Target target_;
  IdentityCheckOptions identity_;
};

}  // namespace netlab::recon
