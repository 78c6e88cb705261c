#include "app/gui/timeline.h"

#include <QMouseEvent>
#include <QPainter>
#include <algorithm>
#include <cmath>

namespace netlab::gui {

Timeline::Timeline(QWidget* parent) : QWidget(parent) {
  setMinimumHeight(24);
  setToolTip(
      "Frames; red marks (above): labels kept for review; magenta marks (below): knots with no "
      "label that other cameras see. Click or drag to go to a frame.");
}

double Timeline::XOf(int t) const {
  const double margin = 6.0;
  return margin + (width() - 2 * margin) * (frames_ > 1 ? double(t) / (frames_ - 1) : 0.0);
}

int Timeline::FrameAt(double x) const {
  const double margin = 6.0;
  const double f = (x - margin) / std::max(1.0, width() - 2 * margin) * (frames_ - 1);
  return std::clamp(static_cast<int>(std::lround(f)), 0, std::max(0, frames_ - 1));
}

void Timeline::paintEvent(QPaintEvent*) {
  QPainter p(this);
  p.fillRect(rect(), palette().window());
  const int mid = height() / 2;
  p.fillRect(QRectF(XOf(0), mid - 3, XOf(frames_ - 1) - XOf(0), 6), QColor(110, 110, 110));
  p.setPen(QColor(230, 60, 50));
  for (int t : review_) p.drawLine(QPointF(XOf(t), 2), QPointF(XOf(t), mid - 4));
  p.setPen(QColor(220, 70, 220));
  for (int t : missing_) p.drawLine(QPointF(XOf(t), mid + 4), QPointF(XOf(t), height() - 2));
  p.setPen(QPen(QColor(60, 140, 255), 3));
  p.drawLine(QPointF(XOf(current_), 2), QPointF(XOf(current_), height() - 2));
}

void Timeline::mousePressEvent(QMouseEvent* event) { emit seek(FrameAt(event->position().x())); }

void Timeline::mouseMoveEvent(QMouseEvent* event) {
  if (event->buttons() & Qt::LeftButton) emit seek(FrameAt(event->position().x()));
}

}  // namespace netlab::gui
