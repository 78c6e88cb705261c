#include "calibration/camera.h"

#include <gtest/gtest.h>

#include <opencv2/calib3d.hpp>
#include <random>

#include "calibration/detect.h"
#include "calibration/rig.h"
#include "calibration/synthetic.h"

namespace netlab::calib {
namespace {

CameraIntrinsics Lens(bool rational) {
  CameraIntrinsics k;
  k.width = 2048;
  k.height = 2048;
  k.fx = 2909.1;
  k.fy = 2905.4;
  k.cx = 1030.2;
  k.cy = 1017.8;
  k.distortion = {-0.12, 0.08, 0.0011, -0.0007, -0.02, 0.0, 0.0, 0.0};
  if (rational) {
    k.rational = true;
    k.distortion[5] = 0.05;
    k.distortion[6] = -0.02;
    k.distortion[7] = 0.01;
  }
  return k;
}

std::vector<Eigen::Vector3d> PointsInView(unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-0.6, 0.6), z(1.5, 4.0);
  std::vector<Eigen::Vector3d> points;
  for (int i = 0; i < 200; ++i) {
    const double depth = z(rng);
    points.emplace_back(u(rng) * depth * 0.5, u(rng) * depth * 0.5, depth);
  }
  return points;
}

// The model is OpenCV's: cv::projectPoints is an independent implementation of the same formula.
TEST(Camera, ProjectionAgreesWithOpenCV) {
  for (bool rational : {false, true}) {
    const CameraIntrinsics k = Lens(rational);
    const auto points = PointsInView(1);
    std::vector<cv::Point3d> object;
    for (const auto& p : points) object.emplace_back(p.x(), p.y(), p.z());
    std::vector<cv::Point2d> image;
    cv::projectPoints(object, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), k.CameraMatrix(),
                      k.DistortionCoefficients(), image);
    for (size_t i = 0; i < points.size(); ++i) {
      const Eigen::Vector2d p = Project(k, points[i]);
      EXPECT_NEAR(p.x(), image[i].x, 1e-8) << i;
      EXPECT_NEAR(p.y(), image[i].y, 1e-8) << i;
    }
  }
}

TEST(Camera, PointsBehindTheCameraDoNotProject) {
  EXPECT_FALSE(Project(Lens(false), Eigen::Vector3d(0.1, 0.2, -1.0)).allFinite());
  EXPECT_FALSE(Project(Lens(false), Eigen::Vector3d(0.1, 0.2, 0.0)).allFinite());
}

TEST(Camera, JacobianMatchesFiniteDifferences) {
  for (bool rational : {false, true}) {
    const CameraIntrinsics k = Lens(rational);
    for (const Eigen::Vector3d& p : PointsInView(2)) {
      const ProjectionJacobian j = ProjectWithJacobian(k, p);
      EXPECT_LT((j.pixel - Project(k, p)).norm(), 1e-9);
      const double h = 1e-6;
      for (int a = 0; a < 3; ++a) {
        Eigen::Vector3d plus = p, minus = p;
        plus[a] += h;
        minus[a] -= h;
        const Eigen::Vector2d d = (Project(k, plus) - Project(k, minus)) / (2 * h);
        EXPECT_LT((d - j.wrt_point.col(a)).norm(), 1e-4 * (1.0 + d.norm()));
      }
      auto params = k.ToParameters();
      for (int a = 0; a < kNumIntrinsics; ++a) {
        CameraIntrinsics plus = k, minus = k;
        auto pp = params, pm = params;
        const double step = 1e-7 * std::max(1.0, std::abs(params[a]));
        pp[a] += step;
        pm[a] -= step;
        plus.FromParameters(pp.data());
        minus.FromParameters(pm.data());
        const Eigen::Vector2d d = (Project(plus, p) - Project(minus, p)) / (2 * step);
        EXPECT_LT((d - j.wrt_intrinsics.col(a)).norm(), 1e-4 * (1.0 + d.norm())) << a;
      }
    }
  }
}

TEST(Camera, UndistortPointInvertsProjection) {
  for (bool rational : {false, true}) {
    const CameraIntrinsics k = Lens(rational);
    for (const Eigen::Vector3d& p : PointsInView(3)) {
      const Eigen::Vector2d x = UndistortPoint(k, Project(k, p));
      EXPECT_NEAR(x.x(), p.x() / p.z(), 1e-10);
      EXPECT_NEAR(x.y(), p.y() / p.z(), 1e-10);
    }
    // Corners of the image, where the distortion is largest.
    for (const Eigen::Vector2d& px : {Eigen::Vector2d(0, 0), Eigen::Vector2d(2047, 2047)}) {
      const Eigen::Vector2d x = UndistortPoint(k, px);
      ASSERT_TRUE(x.allFinite());
      EXPECT_LT((Project(k, Eigen::Vector3d(x.x(), x.y(), 1.0)) - px).norm(), 1e-8);
    }
  }
}

TEST(Camera, UndistortPointAgreesWithOpenCV) {
  const CameraIntrinsics k = Lens(false);
  std::vector<cv::Point2d> pixels = {{100, 120}, {1024, 1024}, {1900, 300}};
  std::vector<cv::Point2d> normalised;
  cv::undistortPoints(
      pixels, normalised, k.CameraMatrix(), k.DistortionCoefficients(), cv::noArray(),
      cv::noArray(), cv::TermCriteria(cv::TermCriteria::COUNT + cv::TermCriteria::EPS, 100, 1e-14));
  for (size_t i = 0; i < pixels.size(); ++i) {
    const Eigen::Vector2d x = UndistortPoint(k, Eigen::Vector2d(pixels[i].x, pixels[i].y));
    EXPECT_NEAR(x.x(), normalised[i].x, 1e-7);
    EXPECT_NEAR(x.y(), normalised[i].y, 1e-7);
  }
}

// An undistorted image shows the target where a distortion-free pinhole would.
TEST(Camera, UndistortedImageMatchesThePinholeProjection) {
  Rig rig = PaperRig(0.5);
  Camera camera = rig.cameras[0];
  camera.intrinsics.distortion[0] = -0.2;  // strong barrel distortion
  const CalibrationTarget board = CalibrationTarget::Board(BoardPattern::Chessboard(9, 6, 0.08));
  Eigen::Matrix3d r;
  r << Eigen::Vector3d(0, -1, 0), Eigen::Vector3d(0, 0, -1), Eigen::Vector3d(1, 0, 0);
  const Rigid3d pose(Eigen::Quaterniond(r), Eigen::Vector3d(0.6, 0.32, 0.73));
  const cv::Mat image = RenderTarget(camera, CameraRays(camera.intrinsics), MakeTargetPrints(board),
                                     pose, RenderOptions{});
  const cv::Mat undistorted = UndistortImage(camera.intrinsics, image);
  const PatternDetection found = DetectPattern(undistorted, board.faces[0].pattern);
  ASSERT_EQ(found.ids.size(), 54u);
  CameraIntrinsics pinhole = camera.intrinsics;
  pinhole.distortion.fill(0.0);
  double worst = 0.0;
  for (size_t i = 0; i < found.ids.size(); ++i) {
    const Eigen::Vector3d x =
        camera.cam_from_world * (pose * board.faces[0].pattern.points[found.ids[i]]);
    worst = std::max(worst, (Project(pinhole, x) - found.pixels[i]).norm());
  }
  EXPECT_LT(worst, 0.3);  // bilinear resampling plus detection
}

TEST(Camera, IntrinsicsValidation) {
  CameraIntrinsics k = Lens(false);
  std::string error;
  EXPECT_TRUE(k.IsValid(&error));
  k.fx = -1;
  EXPECT_FALSE(k.IsValid(&error));
  EXPECT_NE(error.find("focal"), std::string::npos);
}

}  // namespace
}  // namespace netlab::calib
