#pragma once
// The review queue as a table model (model/view: one row per label kept for review, never a
// widget per row): camera, frame, knot, where the label came from, its severity and the reason.
// Rows follow LabelDocument::ReviewItems (frame, then camera, then knot); a view sorts them
// through a QSortFilterProxyModel. The model follows the document's changes by itself.

#include <QAbstractTableModel>
#include <string>
#include <vector>

#include "app/gui/document/label_document.h"

namespace netlab::gui {

class ReviewModel : public QAbstractTableModel {
  Q_OBJECT

 public:
  enum Column { kCamera, kFrame, kKnot, kSource, kSeverity, kReason, kColumns };
  // Roles beyond Qt's: the label's address, for a view that jumps to it.
  enum Role { kCameraRole = Qt::UserRole + 1, kFrameRowRole, kKnotRole };

  // `frame_numbers[t]`: the recording's frame number of frame row t (shown in the table).
  ReviewModel(const LabelDocument* document, std::vector<int> frame_numbers,
              QObject* parent = nullptr);

  int rowCount(const QModelIndex& parent = {}) const override;
  int columnCount(const QModelIndex& parent = {}) const override;
  QVariant data(const QModelIndex& index, int role = Qt::DisplayRole) const override;
  QVariant headerData(int section, Qt::Orientation orientation,
                      int role = Qt::DisplayRole) const override;

  const std::vector<LabelKey>& items() const { return items_; }
  // The row of the item after / before `key` in the queue's order (wrapping); -1 when empty.
  int Next(const LabelKey& key) const;
  int Previous(const LabelKey& key) const;
  // 0 (sure) .. 1 (doubtful): one minus the label's confidence.
  double Severity(const LabelKey& key) const;

 public slots:
  void Refresh();

 private:
  const LabelDocument* document_;
  std::vector<int> frame_numbers_;
  std::vector<LabelKey> items_;
};

// The name of a label's source as the window shows it ("person", "Find Node", ...).
QString SourceName(recon::LabelSource source);

}  // namespace netlab::gui
