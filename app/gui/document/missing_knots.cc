#include "app/gui/document/missing_knots.h"

#include <stdexcept>

namespace netlab::gui {

MissingKnots::MissingKnots(const LabelDocument* document, const calib::Rig* rig,
                           std::vector<int> rig_index, MissingKnotsOptions options,
                           QObject* parent)
    : QObject(parent),
      document_(document),
      rig_(rig),
      rig_index_(std::move(rig_index)),
      options_(options) {
  std::string why;
  if (!options_.IsValid(&why)) throw std::invalid_argument("missing knots: " + why);
  if (rig_index_.size() != document_->labels().cameras.size())
    throw std::invalid_argument("missing knots: one rig camera per camera of the labels");
  // Every frame row now; later only the rows an edit names.
  const int frames = document_->labels().frames();
  by_row_.resize(frames);
  for (int t = 0; t < frames; ++t) {
    by_row_[t] = FindMissingKnots(document_->labels(), *rig_, rig_index_, t, options_);
    size_ += static_cast<int>(by_row_[t].size());
  }
  connect(document_, &LabelDocument::labelsChanged, this, &MissingKnots::Recount);
}

void MissingKnots::Recount(const QList<int>& frames) {
  for (int t : frames) {
    if (t < 0 || t >= static_cast<int>(by_row_.size())) continue;
    size_ -= static_cast<int>(by_row_[t].size());
    by_row_[t] = FindMissingKnots(document_->labels(), *rig_, rig_index_, t, options_);
    size_ += static_cast<int>(by_row_[t].size());
  }
  emit changed(frames);
}

std::vector<LabelKey> MissingKnots::Items() const {
  std::vector<LabelKey> items;
  items.reserve(size_);
  for (const std::vector<MissingKnot>& row : by_row_)
    for (const MissingKnot& m : row) items.emplace_back(m.camera, m.t, m.knot);
  return items;
}

const MissingKnot* MissingKnots::Find(int camera, int t, int knot) const {
  if (t < 0 || t >= static_cast<int>(by_row_.size())) return nullptr;
  for (const MissingKnot& m : by_row_[t])
    if (m.camera == camera && m.knot == knot) return &m;
  return nullptr;
}

std::string MissingKnots::Reason(int camera, int t, int knot) const {
  const MissingKnot* m = Find(camera, t, knot);
  return m ? MissingReason(*m, document_->labels().cameras) : "";
}

std::set<int> MissingKnots::Frames() const {
  std::set<int> frames;
  for (int t = 0; t < static_cast<int>(by_row_.size()); ++t)
    if (!by_row_[t].empty()) frames.insert(t);
  return frames;
}

std::vector<int> MissingKnots::RunFrom(int camera, int t, int knot) const {
  std::vector<int> run;
  for (int u = t; Find(camera, u, knot); ++u) run.push_back(u);
  return run;
}

}  // namespace netlab::gui
