#pragma once
// The camera model: pinhole with Brown-Conrady distortion, OpenCV's model and parameter order so
// that rig.yaml reads directly into cv::FileStorage / cv2 and cv::projectPoints agrees.
//
// A point p_in_cam = (X, Y, Z), Z > 0 in front of the camera, projects as
//   x = X/Z, y = Y/Z, r2 = x^2 + y^2,
//   radial = (1 + k1 r2 + k2 r2^2 + k3 r2^3) / (1 + k4 r2 + k5 r2^2 + k6 r2^3),
//   xd = x radial + 2 p1 x y + p2 (r2 + 2 x^2),   yd = y radial + p1 (r2 + 2 y^2) + 2 p2 x y,
//   u = fx xd + cx,   v = fy yd + cy   (pixels).
// Pixel convention (OpenCV's): the origin is the centre of the top-left pixel, u right, v down.
// k4..k6 are used only by the rational model; otherwise they are 0.
//
// The intrinsic parameter block used by the cost functions holds 12 doubles:
//   fx, fy, cx, cy, k1, k2, p1, p2, k3, k4, k5, k6.

#include <Eigen/Core>
#include <array>
#include <opencv2/core.hpp>
#include <string>

namespace netlab::calib {

inline constexpr int kNumIntrinsics = 12;

struct CameraIntrinsics {
  int width = 0;              // px
  int height = 0;             // px
  double fx = 0.0, fy = 0.0;  // focal lengths, px
  double cx = 0.0, cy = 0.0;  // principal point, px
  // k1, k2, p1, p2, k3, k4, k5, k6 (OpenCV order); k4..k6 only with `rational`.
  std::array<double, 8> distortion{};
  bool rational = false;

  int num_distortion() const { return rational ? 8 : 5; }
  Eigen::Matrix3d K() const;
  cv::Mat CameraMatrix() const;            // 3x3 CV_64F
  cv::Mat DistortionCoefficients() const;  // 1x5 or 1x8 CV_64F
  std::array<double, kNumIntrinsics> ToParameters() const;
  void FromParameters(const double* p);
  // True when sizes and focal lengths are positive and every value finite; else the reason.
  bool IsValid(std::string* error) const;
};

// Distortion of normalised coordinates (the formula above), for double and ceres::Jet.
// `d` points at k1, k2, p1, p2, k3, k4, k5, k6.
template <typename T>
inline void Distort(const T* d, const T& x, const T& y, T* xd, T* yd) {
  const T r2 = x * x + y * y;
  const T r4 = r2 * r2, r6 = r4 * r2;
  const T radial =
      (T(1) + d[0] * r2 + d[1] * r4 + d[4] * r6) / (T(1) + d[5] * r2 + d[6] * r4 + d[7] * r6);
  *xd = x * radial + T(2) * d[2] * x * y + d[3] * (r2 + T(2) * x * x);
  *yd = y * radial + d[2] * (r2 + T(2) * y * y) + T(2) * d[3] * x * y;
}

// Pixel of p_in_cam given the 12-parameter block `k`. Returns false behind the camera (Z <= 0).
template <typename T>
inline bool ProjectPoint(const T* k, const T* p_in_cam, T* pixel) {
  if (!(p_in_cam[2] > T(0))) return false;
  const T x = p_in_cam[0] / p_in_cam[2], y = p_in_cam[1] / p_in_cam[2];
  T xd, yd;
  Distort(k + 4, x, y, &xd, &yd);
  pixel[0] = k[0] * xd + k[2];
  pixel[1] = k[1] * yd + k[3];
  return true;
}

// Pixel of p_in_cam (px). Points behind the camera give NaN.
Eigen::Vector2d Project(const CameraIntrinsics& camera, const Eigen::Vector3d& p_in_cam);

// The Jacobians of Project: d pixel / d p_in_cam (2x3) and d pixel / d intrinsics (2x12).
struct ProjectionJacobian {
  Eigen::Vector2d pixel;
  Eigen::Matrix<double, 2, 3> wrt_point;
  Eigen::Matrix<double, 2, kNumIntrinsics> wrt_intrinsics;
};
ProjectionJacobian ProjectWithJacobian(const CameraIntrinsics& camera,
                                       const Eigen::Vector3d& p_in_cam);

// Normalised undistorted coordinates (x, y) = (X/Z, Y/Z) of a pixel: the inverse of Distort by
// Newton's method. Converges for every pixel whose distortion is invertible (monotonic radial
// function); returns NaN where it does not.
Eigen::Vector2d UndistortPoint(const CameraIntrinsics& camera, const Eigen::Vector2d& pixel);

// The image as a distortion-free pinhole camera with the same K would see it (bilinear).
cv::Mat UndistortImage(const CameraIntrinsics& camera, const cv::Mat& image);

}  // namespace netlab::calib
