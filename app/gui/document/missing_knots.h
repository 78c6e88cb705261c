#pragma once
// The review queue's second kind of item: visible knots with no label where the other cameras,
// the knot's grid neighbours or its motion place them, and the target does not hide them
// (recon::FindMissingKnots, libreconstruct/labeling/missing_knots.h), kept up to date with the
// document. The person then labels such a knot (a Find Node click) or marks it hidden (D);
// either way it leaves the list.
//
//   MissingKnotsOptions options;
//   options.target = LoadTarget("sim.h5", 179.0);        // the project's target, if any
//   MissingKnots missing(&document, &rig, rig_index, options);  // every frame row counted now
//   missing.Items();                                     // (camera, t, knot), queue order
//   missing.Reason(c, t, k);  // "no label; seen in cam0, cam2; expected near (812.4, 1033.0)"
//
// After every labelsChanged the frame rows it names are counted again, with the rows whose points
// they give (options.motion_rows either side), then `changed` is emitted. Without a target a knot
// the target hides from c is listed until the person marks it hidden (RunFrom gives the run of
// frames it is missing in, to mark in one step). Not thread-safe (GUI thread).

#include <QList>
#include <QObject>
#include <set>
#include <string>
#include <vector>

#include "app/gui/document/label_document.h"
#include "calibration/rig.h"
#include "libreconstruct/labeling/missing_knots.h"

namespace netlab::gui {

// The search itself (libreconstruct/labeling/missing_knots.h), named here as the window names it.
using recon::FindMissingKnots;
using recon::MissingKnot;
using recon::MissingKnotsOptions;
using recon::MissingReason;

// The target of a project (project.yaml's `target`): the boxes and balls among the bodies of a
// scenario file (.yaml) or of a `netlab simulate` result (.h5, its /scenario), in the rig's world
// frame, frame number f at time f / fps. InputError naming the file when it cannot be read or
// has no box or ball.
recon::Target LoadTarget(const std::string& path, double fps);

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
  // What it counts with: the rig camera of each store camera, and the options.
  const std::vector<int>& rig_index() const { return rig_index_; }
  const MissingKnotsOptions& options() const { return options_; }

 signals:
  // After every labelsChanged of the document, once the rows it names (`frames`) and their
  // neighbours are counted again.
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
