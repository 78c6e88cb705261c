#include "app/gui/document/review_model.h"

#include <algorithm>

namespace netlab::gui {
namespace {

// The queue's order: frame row, then camera, then knot (LabelDocument::ReviewItems).
bool QueueOrder(const LabelKey& a, const LabelKey& b) {
  return std::tie(std::get<1>(a), std::get<0>(a), std::get<2>(a)) <
         std::tie(std::get<1>(b), std::get<0>(b), std::get<2>(b));
}

}  // namespace

QString SourceName(recon::LabelSource source) {
  switch (source) {
    case recon::LabelSource::kNone:
      return "none";
    case recon::LabelSource::kManual:
      return "person";
    case recon::LabelSource::kFindNode:
      return "Find Node";
    case recon::LabelSource::kFindPath:
      return "Find Path";
    case recon::LabelSource::kFillGrid:
      return "Fill Grid";
    case recon::LabelSource::kTracked:
      return "tracked";
    case recon::LabelSource::kColour:
      return "colour";
    case recon::LabelSource::kImported:
      return "imported";
  }
  return "?";
}

ReviewModel::ReviewModel(const LabelDocument* document, std::vector<int> frame_numbers,
                         QObject* parent)
    : QAbstractTableModel(parent), document_(document), frame_numbers_(std::move(frame_numbers)) {
  items_ = document_->ReviewItems();
  connect(document_, &LabelDocument::labelsChanged, this, &ReviewModel::Refresh);
}

void ReviewModel::Refresh() {
  beginResetModel();
  items_ = document_->ReviewItems();
  endResetModel();
}

int ReviewModel::rowCount(const QModelIndex& parent) const {
  return parent.isValid() ? 0 : static_cast<int>(items_.size());
}

int ReviewModel::columnCount(const QModelIndex& parent) const {
  return parent.isValid() ? 0 : kColumns;
}

double ReviewModel::Severity(const LabelKey& key) const {
  const auto& [c, t, k] = key;
  return 1.0 - std::clamp(static_cast<double>(document_->at(c, t, k).confidence), 0.0, 1.0);
}

QVariant ReviewModel::data(const QModelIndex& index, int role) const {
  if (!index.isValid() || index.row() >= rowCount() || index.column() >= kColumns) return {};
  const LabelKey& key = items_[index.row()];
  const auto& [c, t, k] = key;
  const recon::LabelSet& set = document_->labels();
  if (role == kCameraRole) return c;
  if (role == kFrameRowRole) return t;
  if (role == kKnotRole) return k;
  if (role == Qt::ToolTipRole) return QString::fromStdString(document_->Reason(c, t, k));
  if (role != Qt::DisplayRole && role != Qt::EditRole) return {};
  // EditRole gives sortable values (numbers), DisplayRole the text.
  const bool sort = role == Qt::EditRole;
  switch (index.column()) {
    case kCamera:
      return QString::fromStdString(set.cameras[c]);
    case kFrame:
      return frame_numbers_[t];
    case kKnot:
      if (sort) return k;
      return QString("(%1, %2)").arg(k / set.cols).arg(k % set.cols);
    case kSource:
      return SourceName(document_->at(c, t, k).source);
    case kSeverity:
      if (sort) return Severity(key);
      return QString::number(Severity(key), 'f', 2);
    case kReason: {
      const std::string why = document_->Reason(c, t, k);
      return QString::fromStdString(why.empty() ? "kept for review (no reason recorded)" : why);
    }
  }
  return {};
}

QVariant ReviewModel::headerData(int section, Qt::Orientation orientation, int role) const {
  if (role != Qt::DisplayRole) return {};
  if (orientation == Qt::Vertical) return section + 1;
  static const char* const kNames[kColumns] = {"Camera", "Frame",    "Knot",
                                               "Source", "Severity", "Reason"};
  return section >= 0 && section < kColumns ? QVariant(kNames[section]) : QVariant();
}

int ReviewModel::Next(const LabelKey& key) const {
  if (items_.empty()) return -1;
  const auto it = std::upper_bound(items_.begin(), items_.end(), key, QueueOrder);
  return it == items_.end() ? 0 : static_cast<int>(it - items_.begin());
}

int ReviewModel::Previous(const LabelKey& key) const {
  if (items_.empty()) return -1;
  const auto it = std::lower_bound(items_.begin(), items_.end(), key, QueueOrder);
  return it == items_.begin() ? static_cast<int>(items_.size()) - 1
                              : static_cast<int>(it - items_.begin()) - 1;
}

}  // namespace netlab::gui
