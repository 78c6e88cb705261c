#pragma once
// The review queue as a table model (model/view: one row per item, never a widget per row):
// camera, frame, knot, where the label came from, its severity and the reason. Two kinds of
// item: labels kept for review (LabelDocument::ReviewItems), and, once SetMissing is given,
// missing knots (missing_knots.h: no label where two other cameras see the knot; the source
// column says "missing"). Rows are in the queue's order (frame, then camera, then knot, both
// kinds together); a view sorts them through a QSortFilterProxyModel. The model follows the
// document's changes by itself.

#include <QAbstractTableModel>
#include <string>
#include <vector>

#include "app/gui/document/label_document.h"
#include "app/gui/document/missing_knots.h"

namespace netlab::gui {

class ReviewModel : public QAbstractTableModel {
  Q_OBJECT

 public:
  enum Column { kCamera, kFrame, kKnot, kSource, kSeverity, kReason, kColumns };
  // Roles beyond Qt's: the label's address, for a view that jumps to it.
  enum Role { kCameraRole = Qt::UserRole + 1, kFrameRowRole, kKnotRole, kMissingRole };

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
  // 0 (sure) .. 1 (doubtful): one minus the label's confidence, or what its reason says when
  // that is worse (ReasonSeverity: a label flagged 1555.8 px off is 1 whatever its detector's
  // confidence); a missing knot: 1 (no label).
  double Severity(const LabelKey& key) const;

  // Lists `missing`'s knots too, and follows its changes (null: review items only). `missing`
  // must be over this model's document and outlive the model or the next SetMissing.
  void SetMissing(const MissingKnots* missing);
  // Whether row `row` is a missing knot (not a label under review).
  bool IsMissing(int row) const;

 public slots:
  void Refresh();

 private:
  // Review items and missing knots, merged in the queue's order.
  void Gather();

  const LabelDocument* document_;
  std::vector<int> frame_numbers_;
  std::vector<LabelKey> items_;
  const MissingKnots* missing_ = nullptr;
  std::vector<bool> is_missing_;  // per row of items_
};

// The name of a label's source as the window shows it ("person", "Find Node", ...).
QString SourceName(recon::LabelSource source);

// A review reason's distance from where the label should be, at or beyond which a label is
// surely off its knot (a knot ball's size on the rendered shots): severity 1.
constexpr double kSurePx = 10.0;
// 0 .. 1: how doubtful a review reason makes a label: its largest distance ("4.2 px from the
// epipolar line", "moved 3.1 px otherwise than its neighbours") over kSurePx, 1 when the cameras
// disagree; 0 when it gives none.
double ReasonSeverity(const std::string& reason);

}  // namespace netlab::gui
