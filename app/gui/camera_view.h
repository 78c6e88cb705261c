#pragma once
// One camera's view: its frame at the current index with the labels drawn over it. Zoom at the
// cursor (wheel), pan (drag with the middle or right button), fit (double click with the middle
// button, or the window's key; a fitted view fits again when resized, a zoomed one keeps its
// zoom); the brush radius with Ctrl+wheel; brightness, contrast and gamma
// through a lookup table. The view only draws and forwards: a click, Shift+click, a drag of a label
// and the cursor's pixel go out as signals in image pixels (OpenCV's convention: the centre of the
// top-left pixel is (0, 0)); the window decides what they do.

#include <Eigen/Core>
#include <QImage>
#include <QPointF>
#include <QWidget>
#include <cmath>
#include <opencv2/core.hpp>
#include <optional>
#include <utility>
#include <vector>

#include "app/gui/document/view_overlay.h"

namespace netlab::gui {

// A frame as a view draws it, made off the GUI thread (MakeViewFrame): the image as the cache
// gives it (8-bit BGR, full or half resolution), and a copy reduced by a power of two to about the
// view's size, already toned and in the painter's native format. Painting a 2048^2 image scaled
// down into a 500-pixel view costs the GUI thread ~5 ms per view and frame; the reduced copy is a
// blit.
struct ViewFrame {
  cv::Mat image;      // as given
  int reduction = 1;  // reduced = image shrunk by this factor (1, 2, 4, ...)
  cv::Mat reduced;    // BGR, image / reduction (image itself when 1)
  QImage display;     // reduced after the tone curve, Format_RGB32 (owns its pixels)
};

// The tone curve out = 255 * clamp(gain * (in / 255 - 0.5) + 0.5 + offset)^gamma as a lookup
// table; empty when neutral.
cv::Mat ToneTable(double gain, double offset, double gamma);
// `image` reduced by the largest power of two that keeps at least one image pixel per screen pixel
// at `screen_per_image` screen pixels per image pixel (the view's fit), toned by `tone` (or not,
// when empty). Any thread.
ViewFrame MakeViewFrame(const cv::Mat& image, double screen_per_image, const cv::Mat& tone);

class CameraView : public QWidget {
  Q_OBJECT

 public:
  // The colour of a Fill Grid preview's ghost marks (dashed, over a dark outline): a pink no
  // label has.
  static constexpr QRgb kGhostColour = 0xffff46aa;

  // The caption bar across the view's top (widget pixels): a click on it makes the camera the
  // current one and labels nothing.
  static constexpr int kCaptionHeight = 20;

  explicit CameraView(int camera, QWidget* parent = nullptr);

  int camera() const { return camera_; }
  // The frame (8-bit BGR; empty: `problem` says why nothing is shown), its size in full-
  // resolution pixels (a half-resolution image is drawn scaled up), and what goes over it.
  void SetFrame(const cv::Mat& bgr, int full_width, int full_height, const QString& problem = {});
  // The same with the reduced copy already made (the window's loader makes it off the GUI
  // thread); frame.image empty: `problem` says why nothing is shown.
  void SetFrame(ViewFrame frame, int full_width, int full_height, const QString& problem = {});
  // Screen pixels per pixel of an image `image_width` wide when the view is fitted (what
  // MakeViewFrame needs).
  double FitScreenPerImage(int image_width) const;
  void SetOverlay(ViewOverlay overlay);
  const ViewOverlay& overlay() const { return overlay_; }
  void SetShowLabels(bool show) { show_labels_ = show, update(); }
  void SetShowLinks(bool show) { show_links_ = show, update(); }
  void SetShowEpipolar(bool show) { show_epipolar_ = show, update(); }
  // Display lookup: out = 255 * clamp(gain * (in / 255 - 0.5) + 0.5 + offset)^gamma.
  void SetTone(double gain, double offset, double gamma);
  void SetBrushRadius(double px) { brush_radius_ = px, update(); }
  double brush_radius() const { return brush_radius_; }

  // Image pixel <-> widget point.
  QPointF ToWidget(const Eigen::Vector2d& px) const;
  Eigen::Vector2d ToImage(const QPointF& point) const;
  void Fit();
  // Zooms so that the image pixel `px` is centred with `pixels_across` image pixels across.
  void ZoomTo(const Eigen::Vector2d& px, double pixels_across);
  double scale() const { return scale_; }
  // The label within `radius_widget` widget pixels of the point, nearest first (-1 if none).
  int LabelNear(const QPointF& point, double radius_widget = 8.0) const;
  bool has_image() const { return !frame_.image.empty(); }
  // Paints so far (a benchmark times a frame change until every view has painted it).
  long paints() const { return paints_; }

 signals:
  void clicked(int camera, Eigen::Vector2d px, Qt::KeyboardModifiers modifiers);
  void labelDragged(int camera, int knot, Eigen::Vector2d px);  // on release: one step
  void labelSelected(int camera, int knot);
  void cursorMoved(int camera, Eigen::Vector2d px, QString value);
  void activated(int camera);  // the person works in this view (any press, the caption's too)

 protected:
  void paintEvent(QPaintEvent* event) override;
  void resizeEvent(QResizeEvent* event) override;
  void wheelEvent(QWheelEvent* event) override;
  void mousePressEvent(QMouseEvent* event) override;
  void mouseMoveEvent(QMouseEvent* event) override;
  void mouseReleaseEvent(QMouseEvent* event) override;
  void mouseDoubleClickEvent(QMouseEvent* event) override;

 private:
  void RebuildImage();
  // Draws the frame: the reduced copy when it has a pixel for every screen pixel, else the
  // visible part of the image itself.
  void DrawFrame(QPainter& painter) const;
  void DrawOverlay(QPainter& painter) const;
  void DrawGhosts(QPainter& painter) const;

  int camera_;
  ViewFrame frame_;
  // Zoomed in: the visible pixels as converted for the last paint, kept while the frame, the tone
  // and the visible rectangle stay (a mouse move repaints the brush, not the image).
  mutable QImage zoomed_part_;
  mutable cv::Rect zoomed_rect_;
  cv::Mat tone_;  // ToneTable of the tone below
  int full_width_ = 0, full_height_ = 0;
  QString problem_;
  ViewOverlay overlay_;
  bool show_labels_ = true, show_links_ = true, show_epipolar_ = true;
  double gain_ = 1.0, tone_offset_ = 0.0, gamma_ = 1.0;
  double brush_radius_ = 6.0;
  long paints_ = 0;
  // View transform: widget = (image + 0.5) * scale_ + offset_ (image in full-resolution px).
  double scale_ = 1.0;
  QPointF offset_;
  bool fitted_ = false;
  // The knot pixel and span of the last ZoomTo, until the person zooms or pans: kept on resize.
  std::optional<std::pair<Eigen::Vector2d, double>> zoomed_on_;
  // Whether the view shows the whole image (Fit): a resize fits it again. Zoomed or panned, a
  // resize keeps the scale and the image pixel at the view's centre.
  bool fit_mode_ = true;
  // Interaction.
  std::optional<QPointF> pan_from_;
  int dragging_ = -1;               // the knot being dragged
  bool drag_was_selected_ = false;  // the pressed label was the selected knot's already
  Eigen::Vector2d drag_px_;
  QPointF cursor_;
  bool cursor_inside_ = false;
};

}  // namespace netlab::gui
