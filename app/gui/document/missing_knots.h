#pragma once
// Visible knots with no label: the review queue's second kind of item (netlab issue 18).
//
// Knot k of frame row t is *missing* in camera c when c has neither a label of it nor a hidden
// mark (LabelState::kHidden), while two or more other cameras have accepted labels of it that
// triangulate consistently (recon::TriangulatePoint; every view's reprojection residual within
// max_residual_px: an inconsistent pair never says where the knot should be) to a point in front
// of c whose projection lies inside c's image by margin_px (and is no artefact of the lens model
// folding a point far outside the field of view back into the image). The person then labels
// it (a Find Node click) or marks it hidden (D); either way it leaves the list.
//
//   MissingKnots missing(&document, &rig, rig_index);   // every frame row counted now
//   missing.Items();                                     // (camera, t, knot), queue order
//   missing.Reason(c, t, k);  // "no label; seen in cam0, cam2; expected near (812.4, 1033.0)"
//
// The list follows the document: after every labelsChanged only the frame rows it names are
// counted again, then `changed` is emitted. Only the labels are used, never an image, and the
// target's shape is not known here: a knot the target hides from c is listed as well, until the
// person marks it hidden (on the demo shot's complete labels, 1081 knot-views behind the target
// in 32 runs of consecutive frames: RunFrom gives such a run, to mark in one step). Not
// thread-safe (GUI thread); FindMissingKnots runs on any thread.

#include <Eigen/Core>
#include <QList>
#include <QObject>
#include <set>
#include <string>
#include <vector>

#include "app/gui/document/label_document.h"
#include "calibration/rig.h"
#include "libreconstruct/labels/label_set.h"

namespace netlab::gui {

struct MissingKnotsOptions {
  // Each accepted view's reprojection residual at the triangulated point at most this (px): the
  // engine's epipolar tolerance (LabelEngineOptions::epipolar_tolerance_px).
  double max_residual_px = 2.0;
  // The expected point at least this far inside the image (px): a knot at the very edge cannot
  // be labeled there anyway (the detector's rings need ~20 px).
  double margin_px = 20.0;
  // Only where c has a label (any state) of one of the knot's grid neighbours. Off: a knot the
  // target hides is listed until the person marks it hidden (D, or Shift+D for the frames
  // after it too), and so is every knot the labels expect. On: a knot none of whose neighbours c
  // has labeled (inside the target's shadow, or a patch c lost) is not listed until one is.
  // bench_missing on the demo shot: its labels.h5 lists 8 (all truly visible) off, 6 on; its
  // complete labels (labels_true.h5: every listed knot is behind the target) 1081 in 32 runs of
  // frames off, 502 in 18 on. Off by default: a knot the person is never asked for is the issue
  // this list is for.
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

class MissingKnots : public QObject {
  Q_OBJECT

 public:
  // Counts every frame row of `document` now. `rig` must outlive this; invalid options throw
  // std::invalid_argument.
  MissingKnots(const LabelDocument* document, const calib::Rig* rig, std::vector<int> rig_index,
               MissingKnotsOptions options = {}, QObject* parent = nullptr);

  // Every missing knot as (camera, t, knot), in the queue's order (frame row, camera, knot).
  std::vector<LabelKey> Items() const;
  int size() const { return size_; }
  // The missing knot at (camera, t, knot); null when it is not missing.
  const MissingKnot* Find(int camera, int t, int knot) const;
  // Its reason for the queue ("" when it is not missing).
  std::string Reason(int camera, int t, int knot) const;
  // Frame rows with at least one missing knot.
  std::set<int> Frames() const;
  // The frame rows from t on (t first) in which (camera, knot) is missing without a break; empty
  // when it is not missing in t.
  std::vector<int> RunFrom(int camera, int t, int knot) const;

 signals:
  // After every labelsChanged of the document, once `frames` are counted again.
  void changed(const QList<int>& frames);

 private:
  void Recount(const QList<int>& frames);

  const LabelDocument* document_;
  const calib::Rig* rig_;
  std::vector<int> rig_index_;
  MissingKnotsOptions options_;
  std::vector<std::vector<MissingKnot>> by_row_;  // [t], in (camera, knot) order
  int size_ = 0;
};

}  // namespace netlab::gui
