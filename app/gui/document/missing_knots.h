#pragma once
// The review queue's second kind of item: visible knots with no label where two or more other
// cameras place them (recon::FindMissingKnots, libreconstruct/labeling/missing_knots.h), kept up
// to date with the document. The person then labels such a knot (a Find Node click) or marks it
// hidden (D); either way it leaves the list.
//
//   MissingKnots missing(&document, &rig, rig_index);   // every frame row counted now
//   missing.Items();                                     // (camera, t, knot), queue order
//   missing.Reason(c, t, k);  // "no label; seen in cam0, cam2; expected near (812.4, 1033.0)"
//
// After every labelsChanged only the frame rows it names are counted again, then `changed` is
// emitted. A knot the target hides from c is listed until the person marks it hidden (on the demo
// shot's complete labels, 1081 knot-views behind the target in 32 runs of consecutive frames:
// RunFrom gives such a run, to mark in one step). Not thread-safe (GUI thread).

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
