#include "app/gui/camera_view.h"

#include <QMouseEvent>
#include <QPainter>
#include <QPainterPath>
#include <QResizeEvent>
#include <QWheelEvent>
#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

namespace netlab::gui {

CameraView::CameraView(int camera, QWidget* parent) : QWidget(parent), camera_(camera) {
  setMouseTracking(true);
  setFocusPolicy(Qt::StrongFocus);
  setMinimumSize(160, 160);
  setAttribute(Qt::WA_OpaquePaintEvent);
}

cv::Mat ToneTable(double gain, double offset, double gamma) {
  if (gain == 1.0 && offset == 0.0 && gamma == 1.0) return {};
  cv::Mat lut(1, 256, CV_8U);
  for (int i = 0; i < 256; ++i) {
    const double v = std::clamp(gain * (i / 255.0 - 0.5) + 0.5 + offset, 0.0, 1.0);
    lut.at<uint8_t>(i) = static_cast<uint8_t>(std::lround(255.0 * std::pow(v, gamma)));
  }
  return lut;
}

namespace {

// `bgr` toned and converted to the painter's native 32-bit format (a deep copy).
QImage DisplayImage(const cv::Mat& bgr, const cv::Mat& tone) {
  if (bgr.empty()) return {};
  cv::Mat toned = bgr;
  if (!tone.empty()) cv::LUT(bgr, tone, toned);
  QImage image(toned.cols, toned.rows, QImage::Format_RGB32);
  // Format_RGB32 is 0xffRRGGBB per pixel: B, G, R, 255 in memory, OpenCV's BGRA.
  cv::Mat bgra(toned.rows, toned.cols, CV_8UC4, image.bits(), image.bytesPerLine());
  cv::cvtColor(toned, bgra, cv::COLOR_BGR2BGRA);
  return image;
}

// The largest power of two that still leaves an image pixel (of an image `cols` wide) for every
// screen pixel.
int Reduction(int cols, double screen_per_image) {
  int reduction = 1;
  while (reduction * 2 * screen_per_image <= 1.0 && cols / (reduction * 2) >= 64) reduction *= 2;
  return reduction;
}

}  // namespace

ViewFrame MakeViewFrame(const cv::Mat& image, double screen_per_image, const cv::Mat& tone) {
  ViewFrame frame;
  frame.image = image;
  if (image.empty()) return frame;
  frame.reduction = Reduction(image.cols, screen_per_image);
  // Halving step by step: OpenCV's 2x2 box filter has a fast path that is ~7x faster than one
  // 4x4 reduction, and averages of averages are the 4x4 box average all the same.
  frame.reduced = image;
  for (int r = 1; r < frame.reduction; r *= 2) {
    cv::Mat half;
    cv::resize(frame.reduced, half, cv::Size(frame.reduced.cols / 2, frame.reduced.rows / 2), 0, 0,
               cv::INTER_AREA);
    frame.reduced = half;
  }
  frame.display = DisplayImage(frame.reduced, tone);
  return frame;
}

void CameraView::SetFrame(const cv::Mat& bgr, int full_width, int full_height,
                          const QString& problem) {
  if (full_width > 0) full_width_ = full_width, full_height_ = full_height;
  SetFrame(MakeViewFrame(bgr, bgr.empty() ? 1.0 : FitScreenPerImage(bgr.cols), tone_), full_width,
           full_height, problem);
}

void CameraView::SetFrame(ViewFrame frame, int full_width, int full_height,
                          const QString& problem) {
  frame_ = std::move(frame);
  zoomed_part_ = QImage();
  problem_ = problem;
  if (full_width > 0) full_width_ = full_width, full_height_ = full_height;
  if (!fitted_ && full_width_ > 0) Fit();
  update();
}

double CameraView::FitScreenPerImage(int image_width) const {
  if (full_width_ <= 0 || full_height_ <= 0 || image_width <= 0) return 1.0;
  const double fit = std::min(width() / double(full_width_), height() / double(full_height_));
  return fit * devicePixelRatioF() * full_width_ / image_width;
}

void CameraView::SetOverlay(ViewOverlay overlay) {
  overlay_ = std::move(overlay);
  update();
}

void CameraView::SetTone(double gain, double offset, double gamma) {
  gain_ = gain, tone_offset_ = offset, gamma_ = gamma;
  tone_ = ToneTable(gain, offset, gamma);
  RebuildImage();
  update();
}

void CameraView::RebuildImage() {
  // The reduced copy is small: toning it again on the GUI thread is cheap.
  frame_.display = DisplayImage(frame_.reduced, tone_);
  zoomed_part_ = QImage();
}

QPointF CameraView::ToWidget(const Eigen::Vector2d& px) const {
  return {(px.x() + 0.5) * scale_ + offset_.x(), (px.y() + 0.5) * scale_ + offset_.y()};
}

Eigen::Vector2d CameraView::ToImage(const QPointF& point) const {
  return {(point.x() - offset_.x()) / scale_ - 0.5, (point.y() - offset_.y()) / scale_ - 0.5};
}

void CameraView::Fit() {
  if (full_width_ <= 0) return;
  scale_ = std::min(width() / double(full_width_), height() / double(full_height_));
  offset_ = QPointF((width() - full_width_ * scale_) / 2, (height() - full_height_ * scale_) / 2);
  fitted_ = true;
  zoomed_on_.reset();
  fit_mode_ = true;
  update();
}

void CameraView::ZoomTo(const Eigen::Vector2d& px, double pixels_across) {
  scale_ = std::min(width(), height()) / std::max(pixels_across, 4.0);
  offset_ =
      QPointF(width() / 2.0 - (px.x() + 0.5) * scale_, height() / 2.0 - (px.y() + 0.5) * scale_);
  fitted_ = true;
  zoomed_on_ = std::make_pair(px, pixels_across);
  fit_mode_ = false;
  update();
}

int CameraView::LabelNear(const QPointF& point, double radius_widget) const {
  int best = -1;
  double best_d = radius_widget;
  for (const ViewOverlay::Mark& m : overlay_.labels) {
    const QPointF d = ToWidget(m.px) - point;
    const double dist = std::hypot(d.x(), d.y());
    if (dist <= best_d) best_d = dist, best = m.knot;
  }
  return best;
}

void CameraView::paintEvent(QPaintEvent*) {
  ++paints_;
  QPainter painter(this);
  painter.fillRect(rect(), QColor(24, 24, 24));
  if (has_image()) {
    DrawFrame(painter);
  } else {
    painter.setPen(QColor(255, 120, 90));
    painter.drawText(rect(), Qt::AlignCenter | Qt::TextWordWrap,
                     problem_.isEmpty() ? QString("loading ...") : problem_);
  }
  DrawOverlay(painter);
  // The caption and the focus frame.
  painter.setPen(Qt::white);
  painter.fillRect(QRect(0, 0, width(), kCaptionHeight), QColor(0, 0, 0, 150));
  painter.drawText(QRect(6, 0, width() - 12, kCaptionHeight), Qt::AlignVCenter | Qt::AlignLeft,
                   overlay_.caption);
  if (hasFocus()) {
    painter.setPen(QPen(QColor(90, 160, 255), 2));
    painter.drawRect(rect().adjusted(1, 1, -1, -1));
  }
}

void CameraView::DrawFrame(QPainter& painter) const {
  const cv::Mat& image = frame_.image;
  // Full-resolution pixels per image pixel (a half-resolution image covers the same pixels).
  const double s = full_width_ > 0 ? double(full_width_) / image.cols : 1.0;
  const double screen_per_image = scale_ * s * devicePixelRatioF();
  if (screen_per_image * frame_.reduction <= 1.0 + 1e-6) {
    // Zoomed out: the reduced copy has a pixel for every screen pixel (a near 1:1 blit).
    const QRectF target(offset_.x(), offset_.y(), image.cols * s * scale_, image.rows * s * scale_);
    painter.setRenderHint(QPainter::SmoothPixmapTransform, true);
    painter.drawImage(target, frame_.display);
    return;
  }
  // Zoomed in: only the visible image pixels, toned and converted here, drawn as squares.
  const Eigen::Vector2d a = ToImage(QPointF(0, 0)) / s, b = ToImage(QPointF(width(), height())) / s;
  const int x0 = std::clamp(static_cast<int>(std::floor(a.x())), 0, image.cols);
  const int y0 = std::clamp(static_cast<int>(std::floor(a.y())), 0, image.rows);
  const int x1 = std::clamp(static_cast<int>(std::ceil(b.x())) + 1, 0, image.cols);
  const int y1 = std::clamp(static_cast<int>(std::ceil(b.y())) + 1, 0, image.rows);
  if (x1 <= x0 || y1 <= y0) return;
  const cv::Rect visible(x0, y0, x1 - x0, y1 - y0);
  if (zoomed_part_.isNull() || visible != zoomed_rect_) {
    zoomed_part_ = DisplayImage(image(visible), tone_);
    zoomed_rect_ = visible;
  }
  const QImage& part = zoomed_part_;
  const QRectF target(offset_.x() + x0 * s * scale_, offset_.y() + y0 * s * scale_,
                      (x1 - x0) * s * scale_, (y1 - y0) * s * scale_);
  painter.setRenderHint(QPainter::SmoothPixmapTransform, screen_per_image < 1.0);
  painter.drawImage(target, part);
}

void CameraView::DrawOverlay(QPainter& painter) const {
  painter.setRenderHint(QPainter::Antialiasing, true);
  if (show_epipolar_) {
    painter.setPen(QPen(QColor(255, 230, 0, 170), 1.2, Qt::DashLine));
    for (const auto& curve : overlay_.epipolar) {
      QPainterPath path;
      for (size_t i = 0; i < curve.size(); ++i)
        i == 0 ? path.moveTo(ToWidget(curve[i])) : path.lineTo(ToWidget(curve[i]));
      painter.drawPath(path);
    }
  }
  if (show_links_) {
    painter.setPen(QPen(QColor(120, 200, 255, 140), 1.0));
    for (const auto& [a, b] : overlay_.links) painter.drawLine(ToWidget(a), ToWidget(b));
  }
  if (!overlay_.simulated.empty() || !overlay_.simulated_links.empty()) {
    painter.setPen(QPen(overlay_.simulated_colour, 1.2));
    for (const auto& [a, b] : overlay_.simulated_links) painter.drawLine(ToWidget(a), ToWidget(b));
    // Larger than a label's circle, so that a simulated knot on its label rings it.
    const double h = std::clamp(scale_ * 3.0, 3.0, 9.0) + 2.5;
    painter.setBrush(Qt::NoBrush);
    for (const ViewOverlay::Mark& m : overlay_.simulated)
      painter.drawRect(QRectF(ToWidget(m.px) - QPointF(h, h), QSizeF(2 * h, 2 * h)));
  }
  if (show_labels_) {
    const double r = std::clamp(scale_ * 3.0, 3.0, 9.0);
    for (const ViewOverlay::Mark& m : overlay_.labels) {
      const Eigen::Vector2d px = m.knot == dragging_ ? drag_px_ : m.px;
      const QPointF p = ToWidget(px);
      painter.setPen(QPen(m.colour, m.review ? 2.0 : 1.5));
      painter.setBrush(Qt::NoBrush);
      if (m.review)  // a diamond: kept for review
        painter.drawPolygon(QPolygonF({p + QPointF(0, -r - 1), p + QPointF(r + 1, 0),
                                       p + QPointF(0, r + 1), p + QPointF(-r - 1, 0)}));
      else
        painter.drawEllipse(p, r, r);
      painter.drawPoint(p);
      if (m.knot == overlay_.selected_knot) {
        painter.setPen(QPen(Qt::white, 2.0));
        painter.drawEllipse(p, r + 4, r + 4);
      }
    }
  }
  DrawGhosts(painter);
  painter.setPen(QPen(QColor(255, 60, 60), 1.5));
  for (const Eigen::Vector2d& c : overlay_.candidates) {  // several junctions: none taken
    const QPointF p = ToWidget(c);
    painter.drawLine(p + QPointF(-5, -5), p + QPointF(5, 5));
    painter.drawLine(p + QPointF(-5, 5), p + QPointF(5, -5));
  }
  if (overlay_.reprojected) {
    const QPointF p = ToWidget(*overlay_.reprojected);
    painter.setPen(QPen(QColor(255, 80, 255), 1.5));
    painter.drawLine(p + QPointF(-7, 0), p + QPointF(7, 0));
    painter.drawLine(p + QPointF(0, -7), p + QPointF(0, 7));
  }
  if (overlay_.expected) {  // a missing knot: a dashed ring around where it is expected
    const QPointF p = ToWidget(*overlay_.expected);
    painter.setPen(QPen(QColor(255, 80, 255), 2.0, Qt::DashLine));
    painter.setBrush(Qt::NoBrush);
    const double r = std::clamp(scale_ * 8.0, 12.0, 40.0);
    painter.drawEllipse(p, r, r);
  }
  if (cursor_inside_ && !pan_from_ && dragging_ < 0) {  // the brush
    painter.setPen(QPen(QColor(255, 255, 255, 150), 1.0, Qt::DotLine));
    painter.setBrush(Qt::NoBrush);
    painter.drawEllipse(cursor_, brush_radius_ * scale_, brush_radius_ * scale_);
  }
}

void CameraView::DrawGhosts(QPainter& painter) const {
  if (overlay_.ghosts.empty()) return;
  // Larger than a label's mark, so a ghost round a label (kToReview) rings it.
  const double r = std::clamp(scale_ * 3.0, 3.0, 9.0) + 3.0;
  const auto diamond = [](const QPointF& p, double d) {
    return QPolygonF(
        {p + QPointF(0, -d), p + QPointF(d, 0), p + QPointF(0, d), p + QPointF(-d, 0)});
  };
  // Each mark twice: a dark outline under a dashed pink line, visible on any yarn or background.
  QPen outline(QColor(0, 0, 0, 170), 3.5);
  QPen dashed(QColor::fromRgb(kGhostColour), 1.8, Qt::CustomDashLine);
  dashed.setDashPattern({2.5, 1.5});
  painter.setBrush(Qt::NoBrush);
  for (const QPen& pen : {outline, dashed}) {
    painter.setPen(pen);
    for (const ViewOverlay::Ghost& g : overlay_.ghosts) {
      const QPointF p = ToWidget(g.px);
      switch (g.kind) {
        case ViewOverlay::Ghost::kNew:
        case ViewOverlay::Ghost::kChanged:
          if (g.kind == ViewOverlay::Ghost::kChanged && g.from.allFinite())
            painter.drawLine(ToWidget(g.from), p);
          if (g.review)
            painter.drawPolygon(diamond(p, r + 1));
          else
            painter.drawEllipse(p, r, r);
          break;
        case ViewOverlay::Ghost::kToReview: painter.drawPolygon(diamond(p, r + 3)); break;
        case ViewOverlay::Ghost::kRemoved:
          painter.drawLine(p + QPointF(-r, -r), p + QPointF(r, r));
          painter.drawLine(p + QPointF(-r, r), p + QPointF(r, -r));
          break;
      }
    }
  }
}

void CameraView::resizeEvent(QResizeEvent* event) {
  if (fitted_) {
    // A view zoomed onto a knot stays on it (a view shown alone is resized after the zoom); a
    // fitted view fits again; one the person zoomed or panned keeps its scale and the pixel at
    // its centre (a bar shown above the views does not lose the person's zoom).
    if (zoomed_on_) {
      ZoomTo(zoomed_on_->first, zoomed_on_->second);
    } else if (fit_mode_ || !event->oldSize().isValid()) {
      Fit();
    } else {
      const QSize grown = event->size() - event->oldSize();
      offset_ += QPointF(grown.width() / 2.0, grown.height() / 2.0);
      update();
    }
  }
  // A larger view (maximised) needs a finer reduced copy: made once here, not at every paint.
  if (has_image() &&
      Reduction(frame_.image.cols, FitScreenPerImage(frame_.image.cols)) != frame_.reduction)
    frame_ = MakeViewFrame(frame_.image, FitScreenPerImage(frame_.image.cols), tone_);
}

void CameraView::wheelEvent(QWheelEvent* event) {
  const double steps = event->angleDelta().y() / 120.0;
  if (event->modifiers() & Qt::ControlModifier) {  // the brush
    SetBrushRadius(std::clamp(brush_radius_ * std::pow(1.15, steps), 2.0, 60.0));
    return;
  }
  // Zoom about the cursor: the image pixel under it stays put.
  const QPointF at = event->position();
  const Eigen::Vector2d px = ToImage(at);
  scale_ = std::clamp(scale_ * std::pow(1.25, steps), 0.02, 64.0);
  zoomed_on_.reset();
  fit_mode_ = false;
  offset_ = at - QPointF((px.x() + 0.5) * scale_, (px.y() + 0.5) * scale_);
  update();
}

void CameraView::mousePressEvent(QMouseEvent* event) {
  setFocus();
  emit activated(camera_);
  const bool pan = event->button() == Qt::MiddleButton || event->button() == Qt::RightButton;
  if (pan) {
    pan_from_ = event->position();
    return;
  }
  if (event->button() != Qt::LeftButton) return;
  // On the caption bar: the camera picked, nothing labeled.
  if (event->position().y() < kCaptionHeight) return;
  // On a label without Shift: select it (and maybe drag it); elsewhere: a click for the tools.
  const int near = (event->modifiers() & Qt::ShiftModifier) ? -1 : LabelNear(event->position());
  if (near >= 0) {
    dragging_ = near;
    drag_was_selected_ = near == overlay_.selected_knot;
    for (const auto& m : overlay_.labels)
      if (m.knot == near) drag_px_ = m.px;
    emit labelSelected(camera_, near);
    return;
  }
  emit clicked(camera_, ToImage(event->position()), event->modifiers());
}

void CameraView::mouseMoveEvent(QMouseEvent* event) {
  cursor_ = event->position();
  cursor_inside_ = true;
  if (pan_from_) {
    offset_ += event->position() - *pan_from_;
    zoomed_on_.reset();
    fit_mode_ = false;
    pan_from_ = event->position();
  } else if (dragging_ >= 0) {
    drag_px_ = ToImage(event->position());
  }
  // The pixel under the cursor and its value.
  const Eigen::Vector2d px = ToImage(event->position());
  QString value;
  const cv::Mat& image = frame_.image;
  if (!image.empty() && full_width_ > 0) {
    const double s = double(image.cols) / full_width_;
    const int x = static_cast<int>(std::lround(px.x() * s));
    const int y = static_cast<int>(std::lround(px.y() * s));
    if (x >= 0 && y >= 0 && x < image.cols && y < image.rows) {
      const cv::Vec3b v = image.at<cv::Vec3b>(y, x);
      value = QString("RGB %1 %2 %3").arg(v[2]).arg(v[1]).arg(v[0]);
    }
  }
  emit cursorMoved(camera_, px, value);
  update();
}

void CameraView::mouseReleaseEvent(QMouseEvent* event) {
  if (pan_from_ && (event->button() == Qt::MiddleButton || event->button() == Qt::RightButton)) {
    pan_from_.reset();
    return;
  }
  if (dragging_ >= 0 && event->button() == Qt::LeftButton) {
    const int knot = dragging_;
    dragging_ = -1;
    Eigen::Vector2d original(0, 0);
    for (const auto& m : overlay_.labels)
      if (m.knot == knot) original = m.px;
    // A drag of less than a screen pixel is a selection, not a move.
    // A click on the selected knot's own label is a click for the tools (Find Node there, as
    // the review message says a click fixes), not a selection again.
    if ((ToWidget(drag_px_) - ToWidget(original)).manhattanLength() >= 1.0)
      emit labelDragged(camera_, knot, drag_px_);
    else if (drag_was_selected_)
      emit clicked(camera_, ToImage(event->position()), event->modifiers());
    update();
  }
}

void CameraView::mouseDoubleClickEvent(QMouseEvent* event) {
  if (event->button() == Qt::MiddleButton) Fit();
}

}  // namespace netlab::gui
