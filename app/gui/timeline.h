#pragma once
// The timeline under the views: the frame range as a bar, the playhead, a mark above the bar at
// every frame that has labels kept for review (red) and one below it at every frame with missing
// knots (magenta). Click or drag to seek.

#include <QWidget>
#include <set>

namespace netlab::gui {

class Timeline : public QWidget {
  Q_OBJECT

 public:
  explicit Timeline(QWidget* parent = nullptr);
  void SetRange(int frames) { frames_ = frames, update(); }
  void SetCurrent(int t) { current_ = t, update(); }
  void SetReviewFrames(std::set<int> frames) { review_ = std::move(frames), update(); }
  void SetMissingFrames(std::set<int> frames) { missing_ = std::move(frames), update(); }
  const std::set<int>& review_frames() const { return review_; }
  const std::set<int>& missing_frames() const { return missing_; }
  QSize sizeHint() const override { return {600, 28}; }

 signals:
  void seek(int t);

 protected:
  void paintEvent(QPaintEvent* event) override;
  void mousePressEvent(QMouseEvent* event) override;
  void mouseMoveEvent(QMouseEvent* event) override;

 private:
  int FrameAt(double x) const;
  double XOf(int t) const;

  int frames_ = 1, current_ = 0;
  std::set<int> review_;
  std::set<int> missing_;
};

}  // namespace netlab::gui
