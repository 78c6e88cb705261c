#include "app/gui/document/review_model.h"

#include <QRegularExpression>
#include <algorithm>

namespace netlab::gui {
namespace {

// The queue's order: frame row, then camera, then knot (LabelDocument::ReviewItems).
constexpr LabelKey::ByFrame QueueOrder;

}  // namespace

QString SourceName(recon::LabelSource source) {
  switch (source) {
    case recon::LabelSource::kNone: return "none";
    case recon::LabelSource::kManual: return "person";
    case recon::LabelSource::kFindNode: return "Find Node";
    case recon::LabelSource::kFindPath: return "Find Path";
    case recon::LabelSource::kFillGrid: return "Fill Grid";
    case recon::LabelSource::kTracked: return "tracked";
    case recon::LabelSource::kColour: return "colour";
    case recon::LabelSource::kImported: return "imported";
    case recon::LabelSource::kProjected: return "other cameras";
  }
  return "?";
}

ReviewModel::ReviewModel(const LabelDocument* document, std::vector<int> frame_numbers,
                         QObject* parent)
    : QAbstractTableModel(parent), document_(document), frame_numbers_(std::move(frame_numbers)) {
  Gather();
  connect(document_, &LabelDocument::labelsChanged, this, &ReviewModel::Refresh);
  // A reason given after its label's edit: the same rows, their severity and reason anew.
  connect(document_, &LabelDocument::reasonsChanged, this, [this] {
    if (!items_.empty()) emit dataChanged(index(0, kSeverity), index(rowCount() - 1, kReason));
  });
}

void ReviewModel::Refresh() {
  beginResetModel();
  Gather();
  endResetModel();
}

void ReviewModel::Gather() {
  items_ = document_->ReviewItems();
  is_missing_.assign(items_.size(), false);
  if (!missing_) return;
  // Both kinds in the queue's order (a knot is never both: a missing one has no label).
  const std::vector<LabelKey> missing = missing_->Items();
  std::vector<LabelKey> merged;
  std::vector<bool> kinds;
  merged.reserve(items_.size() + missing.size());
  size_t i = 0, j = 0;
  while (i < items_.size() || j < missing.size()) {
    const bool take_missing =
        i == items_.size() || (j < missing.size() && QueueOrder(missing[j], items_[i]));
    merged.push_back(take_missing ? missing[j++] : items_[i++]);
    kinds.push_back(take_missing);
  }
  items_ = std::move(merged);
  is_missing_ = std::move(kinds);
}

void ReviewModel::SetMissing(const MissingKnots* missing) {
  if (missing_) disconnect(missing_, nullptr, this, nullptr);
  missing_ = missing;
  // MissingKnots::changed follows every labelsChanged of the document: one refresh per edit.
  disconnect(document_, &LabelDocument::labelsChanged, this, &ReviewModel::Refresh);
  if (missing_)
    connect(missing_, &MissingKnots::changed, this, &ReviewModel::Refresh);
  else
    connect(document_, &LabelDocument::labelsChanged, this, &ReviewModel::Refresh);
  Refresh();
}

bool ReviewModel::IsMissing(int row) const {
  return row >= 0 && row < static_cast<int>(is_missing_.size()) && is_missing_[row];
}

int ReviewModel::rowCount(const QModelIndex& parent) const {
  return parent.isValid() ? 0 : static_cast<int>(items_.size());
}

int ReviewModel::columnCount(const QModelIndex& parent) const {
  return parent.isValid() ? 0 : kColumns;
}

double ReasonSeverity(const std::string& reason) {
  // The cameras' point itself in doubt: nothing says the label is right.
  if (reason.find("disagree") != std::string::npos) return 1.0;
  // Every distance the reason gives ("2.4 px from the epipolar line", "1555.8 px off the point
  // of all the cameras"), the largest over kSurePx.
  static const QRegularExpression distance(
      R"(([0-9]+(?:\.[0-9]+)?) px (?:off|from|otherwise|apart|away|where))");
  double worst = 0.0;
  auto it = distance.globalMatch(QString::fromStdString(reason));
  while (it.hasNext()) worst = std::max(worst, it.next().captured(1).toDouble());
  return std::clamp(worst / kSurePx, 0.0, 1.0);
}

double ReviewModel::Severity(const LabelKey& key) const {
  const auto& [c, t, k] = key;
  if (!document_->at(c, t, k).present()) return 1.0;  // a missing knot: no label at all
  const double doubt =
      1.0 - std::clamp(static_cast<double>(document_->at(c, t, k).confidence), 0.0, 1.0);
  return std::max(doubt, ReasonSeverity(document_->Reason(c, t, k)));
}

QVariant ReviewModel::data(const QModelIndex& index, int role) const {
  if (!index.isValid() || index.row() >= rowCount() || index.column() >= kColumns) return {};
  const LabelKey& key = items_[index.row()];
  const auto& [c, t, k] = key;
  const recon::LabelSet& set = document_->labels();
  if (role == kCameraRole) return c;
  if (role == kFrameRowRole) return t;
  if (role == kKnotRole) return k;
  const bool missing = IsMissing(index.row());
  if (role == kMissingRole) return missing;
  const std::string why = missing ? missing_->Reason(c, t, k) : document_->Reason(c, t, k);
  if (role == Qt::ToolTipRole) return QString::fromStdString(why);
  if (role != Qt::DisplayRole && role != Qt::EditRole) return {};
  // EditRole gives sortable values (numbers), DisplayRole the text.
  const bool sort = role == Qt::EditRole;
  switch (index.column()) {
    case kCamera: return QString::fromStdString(set.cameras[c]);
    case kFrame: return frame_numbers_[t];
    case kKnot:
      if (sort) return k;
      return QString("(%1, %2)").arg(k / set.cols).arg(k % set.cols);
    case kSource: return missing ? QString("missing") : SourceName(document_->at(c, t, k).source);
    case kSeverity:
      if (sort) return Severity(key);
      return QString::number(Severity(key), 'f', 2);
    case kReason:
      return QString::fromStdString(why.empty() ? "kept for review (no reason recorded)" : why);
  }
  return {};
}

QVariant ReviewModel::headerData(int section, Qt::Orientation orientation, int role) const {
  // A first click on Severity puts the worst first.
  if (role == Qt::InitialSortOrderRole && orientation == Qt::Horizontal && section == kSeverity)
    return static_cast<int>(Qt::DescendingOrder);
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
