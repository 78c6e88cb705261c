#include "libreconstruct/labeling/label_store.h"

#include <cmath>
#include <stdexcept>

namespace netlab::recon {
LabelStore::LabelStore(LabelSet labels) : labels_(std::move(labels)) {}

int LabelStore::Apply(const std::string& name, const std::vector<LabelEdit>& edits) {
  const int cameras = static_cast<int>(labels_.cameras.size());
  for (const LabelEdit& e : edits)
    if (e.camera < 0 || e.camera >= cameras || e.t < 0 || e.t >= labels_.frames() || e.knot < 0 ||
        e.knot >= labels_.knots())
      throw std::out_of_range(
          "label store, step '" + name + "': camera " + std::to_string(e.camera) + ", frame row " +
          std::to_string(e.t) + ", knot " + std::to_string(e.knot) + " is outside the " +
          std::to_string(cameras) + " cameras x " + std::to_string(labels_.frames()) +
          " frames x " + std::to_string(labels_.knots()) + " knots");
  Step step{name, {}};
  for (const LabelEdit& e : edits) {
    Label& slot = labels_.at(e.camera, e.t, e.knot);
    if (SameLabel(slot, e.label)) continue;
    step.changes.push_back({e.camera, e.t, e.knot, slot, e.label});
    slot = e.label;
  }
  if (step.changes.empty()) return 0;
  steps_.resize(done_);
  steps_.push_back(std::move(step));
  done_ = steps_.size();
  modified_ = true;
  Notify(Change::kApplied, steps_.back());
  return static_cast<int>(steps_.back().changes.size());
}

std::string LabelStore::UndoName() const { return CanUndo() ? steps_[done_ - 1].name : ""; }
std::string LabelStore::RedoName() const { return CanRedo() ? steps_[done_].name : ""; }

bool LabelStore::Undo() {
  if (!CanUndo()) return false;
  const Step& step = steps_[--done_];
  // In reverse, so that a step touching one label twice comes back to the first state.
  for (auto it = step.changes.rbegin(); it != step.changes.rend(); ++it)
    labels_.at(it->camera, it->t, it->knot) = it->before;
  modified_ = true;
  Notify(Change::kUndone, step);
  return true;
}

bool LabelStore::Redo() {
  if (!CanRedo()) return false;
  const Step& step = steps_[done_++];
  for (const LabelChange& c : step.changes) labels_.at(c.camera, c.t, c.knot) = c.after;
  modified_ = true;
  Notify(Change::kRedone, step);
  return true;
}

void LabelStore::Notify(Change change, const Step& step) const {
  if (!listener_) return;
  std::vector<LabelEdit> now;
  now.reserve(step.changes.size());
  for (const LabelChange& c : step.changes)
    now.push_back({c.camera, c.t, c.knot, labels_.at(c.camera, c.t, c.knot)});
  listener_(change, step.name, now);
}

void LabelStore::SetReasons(const ReviewReasons& reasons) {
  labels_.reasons.clear();
  const int cameras = static_cast<int>(labels_.cameras.size());
  for (const auto& [key, why] : reasons) {
    const auto [c, t, k] = key;
    if (c >= 0 && c < cameras && t >= 0 && t < labels_.frames() && k >= 0 && k < labels_.knots() &&
        labels_.at(c, t, k).present() && labels_.at(c, t, k).state == LabelState::kNeedsReview)
      labels_.reasons[key] = why;
  }
}

void LabelStore::Save(const std::string& path) {
  WriteLabels(path, labels_);
  modified_ = false;
}

LabelStore LabelStore::Load(const std::string& path) { return LabelStore(ReadLabels(path)); }

}  // namespace netlab::recon
