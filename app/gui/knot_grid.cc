#include "app/gui/knot_grid.h"

#include <QKeyEvent>
#include <QMouseEvent>
#include <QPainter>
#include <QToolTip>
#include <algorithm>
#include <cmath>

namespace netlab::gui {

namespace {
constexpr double kMargin = 22.0;     // px for the row and column numbers
constexpr double kMinScaleMm = 1.0;  // the error colours' scale reaches at least this
}  // namespace

KnotGrid::KnotGrid(QWidget* parent) : QWidget(parent) {
  setFocusPolicy(Qt::ClickFocus);
  setMouseTracking(true);
  setToolTip("Click a knot to label it next; arrows move while the grid has the focus.");
}

void KnotGrid::SetNet(int rows, int cols) {
  rows_ = std::max(0, rows);
  cols_ = std::max(0, cols);
  cells_.assign(static_cast<size_t>(rows_) * cols_, Cell{});
  selected_ = -1;
  offered_.clear();
  identified_ = false;
  update();
}

void KnotGrid::SetCells(std::vector<Cell> cells) {
  if (cells.size() != cells_.size()) return;
  cells_ = std::move(cells);
  update();
}

void KnotGrid::SetSelected(int knot) {
  selected_ = knot >= 0 && knot < rows_ * cols_ ? knot : -1;
  update();
}

void KnotGrid::SetOffered(std::vector<int> knots, bool identified) {
  knots.erase(std::remove_if(knots.begin(), knots.end(),
                             [&](int k) { return k < 0 || k >= rows_ * cols_; }),
              knots.end());
  offered_ = std::move(knots);
  identified_ = identified && offered_.size() == 1;
  update();
}

void KnotGrid::SetErrors(std::vector<double> errors_mm, QString source) {
  if (errors_mm.size() != cells_.size()) errors_mm.clear();
  // The scale's top: the largest error, at least 1 mm (a simulation on the labels to a fraction
  // of a micrometre is all green, not its rounding noise in red).
  worst_mm_ = kMinScaleMm;
  for (double e : errors_mm)
    if (std::isfinite(e)) worst_mm_ = std::max(worst_mm_, e);
  errors_mm_ = std::move(errors_mm);
  error_source_ = std::move(source);
  update();
}

QColor KnotGrid::ErrorColour(double fraction) {
  const double f = std::clamp(fraction, 0.0, 1.0);  // green, yellow, red
  return f < 0.5 ? QColor::fromRgbF(2 * f, 0.75, 0.1)
                 : QColor::fromRgbF(1.0, 0.75 * (2 - 2 * f), 0.1);
}

QColor KnotGrid::ErrorColour(int knot) const {
  if (knot < 0 || knot >= static_cast<int>(errors_mm_.size()) || !std::isfinite(errors_mm_[knot]))
    return {};
  return ErrorColour(errors_mm_[knot] / worst_mm_);
}

QString KnotGrid::ErrorLegend() const {
  if (errors_mm_.empty()) return "";
  return QString("%1: 0 (green) to %2 mm (red)").arg(error_source_).arg(worst_mm_, 0, 'g', 3);
}

QString KnotGrid::KnotToolTip(int k) const {
  if (k < 0 || k >= rows_ * cols_) return toolTip();
  const Cell& c = cells_[k];
  QString state = c.hidden            ? "marked hidden here"
                  : c.label.isValid() ? "labeled here"
                                      : "no label here";
  if (std::find(offered_.begin(), offered_.end(), k) != offered_.end())
    state += identified_ ? "; the colours identify it" : "; the colours fit it";
  QString text = QString("knot (%1, %2): %3").arg(k / cols_).arg(k % cols_).arg(state);
  if (!errors_mm_.empty())
    text += std::isfinite(errors_mm_[k])
                ? QString("\n%1: %2 mm").arg(error_source_).arg(errors_mm_[k], 0, 'f', 2)
                : QString("\n%1: not compared").arg(error_source_);
  return text;
}

double KnotGrid::Pitch() const {
  if (rows_ < 1 || cols_ < 1) return 1.0;
  return std::max(4.0, std::min((width() - kMargin - 6) / cols_,
                                (height() - kMargin - 6 - LegendHeight()) / rows_));
}

QPointF KnotGrid::Origin() const {
  const double p = Pitch();
  // Centred in the space right of and below the numbers.
  const double w = p * cols_, h = p * rows_;
  return {kMargin + std::max(0.0, (width() - kMargin - w) / 2) + p / 2,
          kMargin + std::max(0.0, (height() - kMargin - LegendHeight() - h) / 2) + p / 2};
}

QPointF KnotGrid::KnotCentre(int knot) const {
  if (cols_ < 1) return {};
  const double p = Pitch();
  return Origin() + QPointF((knot % cols_) * p, (knot / cols_) * p);
}

int KnotGrid::KnotAt(const QPointF& point) const {
  if (rows_ < 1 || cols_ < 1) return -1;
  const double p = Pitch();
  const QPointF d = (point - Origin()) / p;
  const int col = static_cast<int>(std::lround(d.x())), row = static_cast<int>(std::lround(d.y()));
  if (row < 0 || col < 0 || row >= rows_ || col >= cols_) return -1;
  const QPointF off = point - KnotCentre(row * cols_ + col);
  return std::hypot(off.x(), off.y()) <= 0.5 * p ? row * cols_ + col : -1;
}

void KnotGrid::Pick(int knot) {
  if (knot < 0 || knot >= rows_ * cols_) return;
  SetSelected(knot);
  emit knotPicked(knot);
}

bool KnotGrid::event(QEvent* event) {
  if (event->type() == QEvent::ShortcutOverride) {
    const auto* key_event = static_cast<QKeyEvent*>(event);
    const int key = key_event->key();
    // Plain arrows only: with Ctrl (nudge the label) or Shift (10 frames) they stay the window's.
    if ((key == Qt::Key_Left || key == Qt::Key_Right || key == Qt::Key_Up || key == Qt::Key_Down) &&
        (key_event->modifiers() & ~Qt::KeypadModifier) == Qt::NoModifier) {
      event->accept();  // the grid's, not the window's frame keys
      return true;
    }
  }
  if (event->type() == QEvent::ToolTip && rows_ > 0) {
    auto* help = static_cast<QHelpEvent*>(event);
    const int k = KnotAt(help->pos());
    QToolTip::showText(help->globalPos(), k < 0 ? toolTip() : KnotToolTip(k), this);
    return true;
  }
  return QWidget::event(event);
}

void KnotGrid::keyPressEvent(QKeyEvent* event) {
  if (rows_ < 1 || cols_ < 1 || (event->modifiers() & ~Qt::KeypadModifier) != Qt::NoModifier)
    return QWidget::keyPressEvent(event);
  const int k = std::max(0, selected_);
  int row = k / cols_, col = k % cols_;
  switch (event->key()) {
    case Qt::Key_Left: col = std::max(0, col - 1); break;
    case Qt::Key_Right: col = std::min(cols_ - 1, col + 1); break;
    case Qt::Key_Up: row = std::max(0, row - 1); break;
    case Qt::Key_Down: row = std::min(rows_ - 1, row + 1); break;
    default: return QWidget::keyPressEvent(event);
  }
  Pick(row * cols_ + col);
}

void KnotGrid::mousePressEvent(QMouseEvent* event) {
  if (event->button() != Qt::LeftButton) return QWidget::mousePressEvent(event);
  Pick(KnotAt(event->position()));
}

void KnotGrid::paintEvent(QPaintEvent*) {
  QPainter painter(this);
  painter.setRenderHint(QPainter::Antialiasing);
  painter.fillRect(rect(), palette().window());
  if (rows_ < 1 || cols_ < 1) {
    painter.drawText(rect(), Qt::AlignCenter | Qt::TextWordWrap, "No project open");
    return;
  }
  const double p = Pitch(), r = std::max(2.0, 0.3 * p);
  const QColor ink = palette().windowText().color();
  // The links, then the numbers of rows and columns (every one, or every 2nd / 4th when tight).
  painter.setPen(QPen(QColor(150, 150, 150), 1.0));
  const QPointF o = Origin();
  for (int row = 0; row < rows_; ++row)
    painter.drawLine(o + QPointF(0, row * p), o + QPointF((cols_ - 1) * p, row * p));
  for (int col = 0; col < cols_; ++col)
    painter.drawLine(o + QPointF(col * p, 0), o + QPointF(col * p, (rows_ - 1) * p));
  QFont small = font();
  small.setPointSizeF(std::max(6.0, std::min(9.0, 0.45 * p)));
  painter.setFont(small);
  painter.setPen(ink);
  const int every = p >= 16 ? 1 : p >= 8 ? 2 : 4;
  for (int i = 0; i < std::max(rows_, cols_); i += every) {
    if (i < cols_)
      painter.drawText(QRectF(o.x() + i * p - p / 2, 2, p, kMargin - 4), Qt::AlignCenter,
                       QString::number(i));
    if (i < rows_)
      painter.drawText(QRectF(0, o.y() + i * p - p / 2, kMargin - 4, p),
                       Qt::AlignRight | Qt::AlignVCenter, QString::number(i));
  }
  // The errors, as squares behind the discs, and their scale below the grid.
  if (!errors_mm_.empty()) {
    painter.setPen(Qt::NoPen);
    const double half = r + std::max(2.0, 0.1 * p);  // a frame round the disc
    for (int k = 0; k < rows_ * cols_; ++k) {
      const QColor colour = ErrorColour(k);
      if (!colour.isValid()) continue;
      painter.setBrush(colour);
      painter.drawRect(QRectF(KnotCentre(k) - QPointF(half, half), QSizeF(2 * half, 2 * half)));
    }
    painter.setPen(ink);
    painter.drawText(QRectF(4, height() - LegendHeight(), width() - 8, LegendHeight()),
                     Qt::AlignCenter, ErrorLegend());
  }
  // The discs.
  for (int k = 0; k < rows_ * cols_; ++k) {
    const QPointF c = KnotCentre(k);
    const Cell& cell = cells_[k];
    painter.setPen(QPen(QColor(60, 60, 60), 1.0));
    painter.setBrush(cell.label.isValid() ? QBrush(cell.label) : QBrush(Qt::white));
    painter.drawEllipse(c, r, r);
    if (cell.hidden) {
      painter.setPen(QPen(QColor(90, 90, 90), 1.5));
      painter.drawLine(c + QPointF(-r, -r), c + QPointF(r, r));
    }
  }
  // The colours' offer, then the knot to label.
  painter.setBrush(Qt::NoBrush);
  for (int k : offered_) {
    const double ring = r + (identified_ ? 4.0 : 2.5);
    painter.setPen(QPen(QColor(0, 0, 0, 160), identified_ ? 5.0 : 3.5));
    painter.drawEllipse(KnotCentre(k), ring, ring);
    painter.setPen(QPen(QColor(255, 215, 0), identified_ ? 3.0 : 1.8));
    painter.drawEllipse(KnotCentre(k), ring, ring);
  }
  if (selected_ >= 0) {
    const double ring = r + 1.5;
    painter.setPen(QPen(QColor(30, 110, 255), 2.5));
    painter.drawEllipse(KnotCentre(selected_), ring, ring);
  }
}

}  // namespace netlab::gui
