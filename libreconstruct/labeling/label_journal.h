#pragma once
// The label journal: every step of a LabelStore since the last save, as text beside the labels
// file ("<labels>.journal"), so that the edits survive a crash. The workstation writes it after
// every change of its store and replays it on the next start.
//
//   netlab-journal 1 ROWS COLS FRAMES cam0,cam1,...      the label set it belongs to
//   step applied|undone|redone NAME                       one change of the store
//   CAMERA T KNOT X Y SOURCE CONFIDENCE STATE            each label it changed, as it is now
//   end                                                   (numbers %.17g; "nan" for a hidden mark)
//
// A step without its "end" (cut short by the crash) is left out when the journal is read.

#include <ostream>
#include <string>
#include <vector>

#include "libreconstruct/labeling/label_store.h"
#include "libreconstruct/labels/label_set.h"

namespace netlab::recon {

// "<labels_path>.journal".
std::string LabelJournalPath(const std::string& labels_path);
// The journal's first line for `set`: its net, frame count and cameras.
std::string LabelJournalHeader(const LabelSet& set);
// Appends one change of the store (LabelStore::Listener's arguments) to `out`.
void WriteLabelJournalStep(std::ostream& out, LabelStore::Change change, const std::string& step,
                           const std::vector<LabelEdit>& now);
// Every label the journal at `path` changed, as its last complete step left it, in (camera, t,
// knot) order. InputError naming the file and line when it cannot be opened, is of another label
// set than `set`, or holds a line that is no label of it.
std::vector<LabelEdit> ReadLabelJournal(const std::string& path, const LabelSet& set);

}  // namespace netlab::recon
