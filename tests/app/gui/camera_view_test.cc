// A camera view draws its frame where its pixels are, zoomed out (from the copy reduced off the
// GUI thread) and zoomed in (the visible pixels of the frame itself), and the tone curve applies
// to both. Qt's offscreen platform; the view grabbed to an image and read at known pixels.

#include "app/gui/camera_view.h"

#include <gtest/gtest.h>

#include <QApplication>
#include <QImage>
#include <opencv2/imgproc.hpp>

namespace netlab::gui {
namespace {

// A 2048^2 frame: the left half red, the right half blue, an 8 x 8 green square at pixels
// 1000..1007 (BGR).
cv::Mat TestFrame() {
  cv::Mat bgr(2048, 2048, CV_8UC3, cv::Scalar(0, 0, 200));
  bgr(cv::Rect(1024, 0, 1024, 2048)).setTo(cv::Scalar(200, 0, 0));
  bgr(cv::Rect(1000, 1000, 8, 8)).setTo(cv::Scalar(0, 200, 0));
  return bgr;
}

// The colour the grabbed view shows at image pixel px (its centre; below the caption bar).
QColor ShownAt(CameraView& view, const Eigen::Vector2d& px) {
  const QImage shot = view.grab().toImage();
  const QPointF p = view.ToWidget(px);
  return shot.pixelColor(static_cast<int>(p.x()), static_cast<int>(p.y()));
}

TEST(MakeViewFrame, ReducesByThePowerOfTwoThatKeepsAPixelPerScreenPixel) {
  const cv::Mat bgr = TestFrame();
  EXPECT_EQ(MakeViewFrame(bgr, 0.6, {}).reduction, 1);
  EXPECT_EQ(MakeViewFrame(bgr, 0.3, {}).reduction, 2);
  const ViewFrame f = MakeViewFrame(bgr, 0.23, {});
  ASSERT_EQ(f.reduction, 4);
  EXPECT_EQ(f.reduced.cols, 512);
  EXPECT_EQ(f.display.width(), 512);
  EXPECT_EQ(f.display.format(), QImage::Format_RGB32);
  // The reduction is the 4 x 4 box average: the green square (pixels 1000..1007) becomes reduced
  // pixels 250..251 exactly, and 249 stays all red.
  EXPECT_EQ(f.reduced.at<cv::Vec3b>(250, 250), cv::Vec3b(0, 200, 0));
  EXPECT_EQ(f.reduced.at<cv::Vec3b>(250, 249), cv::Vec3b(0, 0, 200));
  EXPECT_EQ(f.display.pixelColor(250, 250), QColor(0, 200, 0));
}

TEST(CameraView, DrawsTheFrameWherePixelsAreZoomedOutAndZoomedIn) {
  CameraView view(0);
  view.resize(400, 400);
  view.show();
  view.SetFrame(TestFrame(), 2048, 2048);  // fitted: the reduced copy
  EXPECT_EQ(ShownAt(view, {100, 1000}), QColor(200, 0, 0));
  EXPECT_EQ(ShownAt(view, {1900, 1000}), QColor(0, 0, 200));
  // Zoomed in on the green square, 40 image pixels across the view (10 screen px each): the
  // square's first and last pixel green, their neighbours outside red. A shift by one image
  // pixel would move a whole 10 px square.
  view.ZoomTo({1003.5, 1003.5}, 40);
  for (const double x : {1000.0, 1007.0})
    EXPECT_EQ(ShownAt(view, {x, 1003}), QColor(0, 200, 0)) << "x " << x;
  for (const double x : {999.0, 1008.0})
    EXPECT_EQ(ShownAt(view, {x, 1003}), QColor(200, 0, 0)) << "x " << x;
  EXPECT_EQ(ShownAt(view, {1003, 999}), QColor(200, 0, 0));
  EXPECT_EQ(ShownAt(view, {1003, 1008}), QColor(200, 0, 0));
}

TEST(CameraView, AHalfResolutionFrameCoversTheSameFullResolutionPixels) {
  CameraView view(0);
  view.resize(400, 400);
  view.show();
  cv::Mat half;
  cv::resize(TestFrame(), half, cv::Size(1024, 1024), 0, 0, cv::INTER_AREA);
  view.SetFrame(half, 2048, 2048);
  view.ZoomTo({1003.5, 1003.5}, 40);  // in full-resolution pixels
  EXPECT_EQ(ShownAt(view, {1001, 1003}), QColor(0, 200, 0));
  EXPECT_EQ(ShownAt(view, {1006, 1003}), QColor(0, 200, 0));
  EXPECT_EQ(ShownAt(view, {997, 1003}), QColor(200, 0, 0));
}

TEST(CameraView, TheToneCurveAppliesZoomedOutAndZoomedIn) {
  CameraView view(0);
  view.resize(400, 400);
  view.show();
  view.SetFrame(TestFrame(), 2048, 2048);
  // gain 2: out = 255 * clamp(2 * (200 / 255 - 0.5) + 0.5) = 255 (clamped), 0 stays 0.
  view.SetTone(2.0, 0.0, 1.0);
  EXPECT_EQ(ShownAt(view, {100, 1000}), QColor(255, 0, 0));
  view.ZoomTo({1003.5, 1003.5}, 40);
  EXPECT_EQ(ShownAt(view, {1003, 1003}), QColor(0, 255, 0));
  EXPECT_EQ(ShownAt(view, {990, 1003}), QColor(255, 0, 0));
}

// Zoomed in, the converted pixels are kept between paints (a mouse move repaints the brush):
// a new tone, a new frame or a pan must still show at once.
TEST(CameraView, ZoomedInAToneAFrameOrAPanChangeWhatIsShownAtOnce) {
  CameraView view(0);
  view.resize(400, 400);
  view.show();
  view.SetFrame(TestFrame(), 2048, 2048);
  view.ZoomTo({1003.5, 1003.5}, 40);
  EXPECT_EQ(ShownAt(view, {1003, 1003}), QColor(0, 200, 0));
  EXPECT_EQ(ShownAt(view, {1003, 1003}), QColor(0, 200, 0));  // painted again, unchanged
  view.SetTone(2.0, 0.0, 1.0);
  EXPECT_EQ(ShownAt(view, {1003, 1003}), QColor(0, 255, 0));
  view.SetTone(1.0, 0.0, 1.0);
  cv::Mat blue = TestFrame();
  blue(cv::Rect(1000, 1000, 8, 8)).setTo(cv::Scalar(200, 0, 0));
  view.SetFrame(blue, 2048, 2048);
  EXPECT_EQ(ShownAt(view, {1003, 1003}), QColor(0, 0, 200));
  view.ZoomTo({1900.5, 1003.5}, 40);  // over the blue half
  EXPECT_EQ(ShownAt(view, {1900, 1003}), QColor(0, 0, 200));
}

}  // namespace
}  // namespace netlab::gui
