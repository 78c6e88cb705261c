#pragma once
// The label store behind the labeling tools and the GUI: every knot's 2D label per camera and
// frame (libreconstruct/labels/label_set.h: position, source, confidence, state), changed only
// through operations that undo and redo as one step each, saved without loss.
//
//   LabelStore store(LabelSet::Empty(11, 11, cameras, frames));
//   store.Apply("Find Node", {{camera, t, knot, label}});   // one undoable step
//   store.Undo();  store.Redo();
//   store.Save("labels.h5");                               // .partial + rename: a crash
//                                                          // mid-save keeps the old file
//
// A step that changes nothing is not recorded. A new step after Undo drops the steps that could
// have been redone (as every editor does). A listener (SetListener) hears of every change: a
// window mirrors the steps in its undo stack, journals them and redraws what changed.

#include <functional>
#include <string>
#include <vector>

#include "libreconstruct/labels/label_set.h"

namespace netlab::recon {

struct LabelEdit {
  int camera = 0, t = 0, knot = 0;  // index into the label set's cameras, frame row, knot
  Label label;                      // the new label (Label{} removes it)
};

class LabelStore {
 public:
  explicit LabelStore(LabelSet labels);

  // What a change was: a new step (Apply), or a step taken back (Undo) or done again (Redo).
  enum class Change { kApplied, kUndone, kRedone };
  // Called after every change with the step's name and the labels it changed, as they are now
  // (a label the step changed twice is listed twice). Called on the thread that changed the
  // store.
  using Listener = std::function<void(Change change, const std::string& step,
                                      const std::vector<LabelEdit>& now)>;
  void SetListener(Listener listener) { listener_ = std::move(listener); }

  const LabelSet& labels() const { return labels_; }
  const Label& at(int camera, int t, int knot) const { return labels_.at(camera, t, knot); }

  // Applies the edits as one step named `name`. Throws std::out_of_range (naming the edit) for
  // an index outside the set, before changing anything. Returns the number of labels changed.
  int Apply(const std::string& name, const std::vector<LabelEdit>& edits);

  bool CanUndo() const { return done_ > 0; }
  bool CanRedo() const { return done_ < steps_.size(); }
  // The name of the step Undo / Redo would take back / do again ("" if none).
  std::string UndoName() const;
  std::string RedoName() const;
  bool Undo();
  bool Redo();

  // Why labels are under review, saved with them (metadata, not an undoable step): the reasons
  // of labels under review are kept, the others dropped.
  void SetReasons(const ReviewReasons& reasons);

  // Whether anything changed since the last Save or Load.
  bool modified() const { return modified_; }
  // labels.h5 through "<path>.partial" and a rename (libreconstruct/labels/label_set.h:
  // WriteLabels).
  void Save(const std::string& path);
  static LabelStore Load(const std::string& path);

 private:
  struct LabelChange {
    int camera, t, knot;
    Label before, after;
  };
  struct Step {
    std::string name;
    std::vector<LabelChange> changes;
  };
  // Tells the listener, if any, of `step` as it is now.
  void Notify(Change change, const Step& step) const;
  LabelSet labels_;
  std::vector<Step> steps_;
  size_t done_ = 0;  // steps_[0, done_) are applied
  bool modified_ = false;
  Listener listener_;
};

}  // namespace netlab::recon
