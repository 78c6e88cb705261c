#pragma once
// The labels a person edits in the window: the label store (libreconstruct/labeling/
// label_store.h) with its steps mirrored in one QUndoStack, the reasons of labels kept for review,
// the file they are saved to, and a journal that keeps every edit since the last save.
//
//   LabelDocument doc(labels, "labels.h5");
//   doc.Apply("Move (3, 4)", {{camera, t, knot, label}});  // one undo step
//   doc.undo_stack()->undo();                              // the store's Undo
//   doc.Save();                                            // labels.h5.partial + rename
//
// Every change of the store, whoever made it (the person, or an engine tool run on the GUI
// thread through store()), becomes one QUndoStack command and is appended to the journal
// ("<labels>.journal"; its format: libreconstruct/labeling/label_journal.h) before labelsChanged
// is emitted. After a crash the journal replays every
// edit since the last save (Recover); Save empties it. Not thread-safe: GUI thread only.

#include <QObject>
#include <QUndoStack>
#include <fstream>
#include <map>
#include <set>
#include <string>
#include <tuple>
#include <vector>

#include "libreconstruct/labeling/label_engine.h"
#include "libreconstruct/labeling/label_journal.h"
#include "libreconstruct/labeling/label_store.h"
#include "libreconstruct/labels/label_set.h"

namespace netlab::gui {

// A label's address (camera index, frame row, knot), the labels' own.
using LabelKey = recon::LabelAddress;

class LabelDocument : public QObject {
  Q_OBJECT

 public:
  // `labels`: what is on disk (or an empty set of the right shape); saved to `labels_path`.
  LabelDocument(recon::LabelSet labels, std::string labels_path, QObject* parent = nullptr);
  ~LabelDocument() override;

  const recon::LabelSet& labels() const { return store_.labels(); }
  const recon::Label& at(int camera, int t, int knot) const { return store_.at(camera, t, knot); }
  // The store for an engine on the GUI thread: each step it applies is one undo step here.
  recon::LabelStore* store() { return &store_; }
  QUndoStack* undo_stack() { return &undo_; }

  // Applies the edits as one undoable step named `name`; returns the labels changed (0: no step).
  int Apply(const std::string& name, const std::vector<recon::LabelEdit>& edits);

  // Why (camera, t, knot) is under review ("" when unknown or it is not).
  std::string Reason(int camera, int t, int knot) const;
  // Remembers the engine's reasons (they outlive the labels' state: Reason checks the state).
  void MergeReasons(const recon::ReviewReasons& reasons);
  // Every label under review, in (frame, camera, knot) order.
  std::vector<LabelKey> ReviewItems() const;
  // Frame rows with at least one label under review.
  std::set<int> ReviewFrames() const;

  bool modified() const { return !undo_.isClean(); }
  const std::string& labels_path() const { return labels_path_; }
  // Saves to labels_path() through "<path>.partial" and a rename, then empties the journal.
  // Throws std::runtime_error (the file on disk unchanged) when it cannot.
  void Save();

  // The journal beside the labels file, and whether one is left from a session that ended
  // without saving.
  static std::string JournalPath(const std::string& labels_path) {
    return recon::LabelJournalPath(labels_path);
  }
  static bool HasJournal(const std::string& labels_path);
  // Replays the journal left by an earlier session as one step "Recover unsaved edits"; returns
  // the labels restored. netlab::InputError naming the journal and line when it is not this
  // label set's (other cameras, frames or net) or is damaged past its last complete step.
  int Recover();
  // Deletes the journal left by an earlier session.
  void DiscardJournal();

 signals:
  // Labels of these frame rows changed (an edit, undo or redo).
  void labelsChanged(const QList<int>& frames);
  // MergeReasons changed a reason (the engine says why after its edits are applied: a view of
  // the reasons shown with those edits is stale until this).
  void reasonsChanged();
  void modifiedChanged(bool modified);
  // The journal could not be written (once per document): edits are not crash-safe.
  void journalFailed(const QString& message);

 private:
  class StoreStep;
  void OnStoreChanged(recon::LabelStore::Change change, const std::string& step,
                      const std::vector<recon::LabelEdit>& now);
  void Journal(recon::LabelStore::Change change, const std::string& step,
               const std::vector<recon::LabelEdit>& now);

  recon::LabelStore store_;
  QUndoStack undo_;
  std::string labels_path_;
  recon::ReviewReasons reasons_;
  std::set<LabelKey, LabelKey::ByFrame> review_;  // under review, in the queue's order
  std::ofstream journal_;
  bool journal_failed_ = false;
  bool replaying_undo_ = false;  // the stack is driving the store: do not push again
};

}  // namespace netlab::gui
