#include "app/gui/document/label_document.h"

#include <QUndoCommand>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <sstream>

#include "common/errors.h"
#include "libreconstruct/labeling/label_journal.h"

namespace netlab::gui {
namespace {

namespace fs = std::filesystem;

}  // namespace

// One step of the store as a command of the stack. Pushed after the store applied it (so the
// first redo does nothing); undo and redo drive the store, whose listener then journals and
// notifies.
class LabelDocument::StoreStep : public QUndoCommand {
 public:
  StoreStep(LabelDocument* doc, const std::string& name)
      : QUndoCommand(QString::fromStdString(name)), doc_(doc) {}
  void undo() override {
    Drive([this] { doc_->store_.Undo(); });
  }
  void redo() override {
    if (first_) {
      first_ = false;
      return;
    }
    Drive([this] { doc_->store_.Redo(); });
  }

 private:
  template <typename F>
  void Drive(F f) {
    doc_->replaying_undo_ = true;
    f();
    doc_->replaying_undo_ = false;
  }
  LabelDocument* doc_;
  bool first_ = true;
};

LabelDocument::LabelDocument(recon::LabelSet labels, std::string labels_path, QObject* parent)
    : QObject(parent), store_(std::move(labels)), labels_path_(std::move(labels_path)) {
  reasons_ = store_.labels().reasons;  // from the file
  // What is under review at the start.
  const recon::LabelSet& set = store_.labels();
  for (int c = 0; c < static_cast<int>(set.cameras.size()); ++c)
    for (int t = 0; t < set.frames(); ++t)
      for (int k = 0; k < set.knots(); ++k)
        if (set.at(c, t, k).present() && set.at(c, t, k).state == recon::LabelState::kNeedsReview)
          review_.insert({c, t, k});
  store_.SetListener(
      [this](recon::LabelStore::Change change, const std::string& step,
             const std::vector<recon::LabelEdit>& now) { OnStoreChanged(change, step, now); });
  connect(&undo_, &QUndoStack::cleanChanged, this,
          [this](bool clean) { emit modifiedChanged(!clean); });
}

LabelDocument::~LabelDocument() { store_.SetListener({}); }

int LabelDocument::Apply(const std::string& name, const std::vector<recon::LabelEdit>& edits) {
  return store_.Apply(name, edits);
}

void LabelDocument::OnStoreChanged(recon::LabelStore::Change change, const std::string& step,
                                   const std::vector<recon::LabelEdit>& now) {
  // The journal first: an edit the window shows is an edit that survives a crash.
  Journal(change, step, now);
  std::set<int> frames;
  for (const recon::LabelEdit& e : now) {
    frames.insert(e.t);
    if (e.label.present() && e.label.state == recon::LabelState::kNeedsReview)
      review_.insert({e.camera, e.t, e.knot});
    else
      review_.erase({e.camera, e.t, e.knot});
  }
  if (change == recon::LabelStore::Change::kApplied && !replaying_undo_)
    undo_.push(new StoreStep(this, step));
  emit labelsChanged(QList<int>(frames.begin(), frames.end()));
}

void LabelDocument::Journal(recon::LabelStore::Change change, const std::string& step,
                            const std::vector<recon::LabelEdit>& now) {
  if (!journal_.is_open()) {
    journal_.open(JournalPath(labels_path_), std::ios::trunc);
    journal_ << recon::LabelJournalHeader(store_.labels()) << "\n";
  }
  recon::WriteLabelJournalStep(journal_, change, step, now);
  journal_.flush();
  // A journal that cannot be written protects nothing: say so, once.
  if (!journal_ && !journal_failed_) {
    journal_failed_ = true;
    emit journalFailed(QString::fromStdString(
        JournalPath(labels_path_) +
        ": cannot write the edit journal; edits since the last save are lost if netlab stops"));
  }
}

std::string LabelDocument::Reason(int camera, int t, int knot) const {
  if (at(camera, t, knot).state != recon::LabelState::kNeedsReview) return "";
  const auto it = reasons_.find({camera, t, knot});
  return it == reasons_.end() ? "" : it->second;
}

void LabelDocument::MergeReasons(const recon::ReviewReasons& reasons) {
  bool changed = false;
  for (const auto& [key, why] : reasons) {
    std::string& held = reasons_[key];
    changed = changed || held != why;
    held = why;
  }
  if (changed) emit reasonsChanged();
}

std::vector<LabelKey> LabelDocument::ReviewItems() const {
  return {review_.begin(), review_.end()};
}

std::set<int> LabelDocument::ReviewFrames() const {
  std::set<int> frames;
  for (const LabelKey& item : review_) frames.insert(item.t);
  return frames;
}

void LabelDocument::Save() {
  store_.SetReasons(reasons_);  // those of the labels still under review go into the file
  store_.Save(labels_path_);    // .partial + rename: on failure the old file stays
  undo_.setClean();
  if (journal_.is_open()) journal_.close();
  std::error_code ignored;
  fs::remove(JournalPath(labels_path_), ignored);
}

bool LabelDocument::HasJournal(const std::string& labels_path) {
  return fs::exists(JournalPath(labels_path));
}

int LabelDocument::Recover() {
  const std::string path = JournalPath(labels_path_);
  const std::vector<recon::LabelEdit> edits = recon::ReadLabelJournal(path, store_.labels());
  // The old journal stays until the recovered step is in the new one.
  const std::string kept = path + ".recovering";
  fs::rename(path, kept);
  const int restored = Apply("Recover unsaved edits", edits);
  std::error_code ignored;
  fs::remove(kept, ignored);
  return restored;
}

void LabelDocument::DiscardJournal() {
  if (journal_.is_open()) journal_.close();
  std::error_code ignored;
  fs::remove(JournalPath(labels_path_), ignored);
}

}  // namespace netlab::gui
