#include "calibration/synthetic.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <opencv2/aruco.hpp>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>
#include <stdexcept>
#include <thread>

namespace netlab::calib {
namespace {

// A chessboard of target.h's convention with a white margin of half a square.
class ChessboardPrint final : public PlanarPrint {
 public:
  explicit ChessboardPrint(const BoardPattern& p) : p_(p) {}
  double Albedo(double x, double y) const override {
    const double s = p_.square, margin = 0.5 * s;
    if (x < -s - margin || y < -s - margin || x > p_.cols * s + margin || y > p_.rows * s + margin)
      return -1.0;
    if (x < -s || y < -s || x >= p_.cols * s || y >= p_.rows * s) return 1.0;
    const int i = static_cast<int>(std::floor(x / s)) + 1,
              j = static_cast<int>(std::floor(y / s)) + 1;
    return (i + j) % 2 == 0 ? 0.0 : 1.0;
  }
  Eigen::Vector2d Min() const override { return p_.extent_min.array() - 0.5 * p_.square; }
  Eigen::Vector2d Max() const override { return p_.extent_max.array() + 0.5 * p_.square; }

 private:
  BoardPattern p_;
};

// A binary texture placed on the plane by an affine map from plane (x, y) to texel (u, v), with a
// white margin around `min`..`max`.
class TexturePrint final : public PlanarPrint {
 public:
  TexturePrint(cv::Mat texture, const Eigen::Matrix<double, 2, 3>& plane_to_texel,
               const Eigen::Vector2d& min, const Eigen::Vector2d& max, double margin,
               double viewer_z)
      : texture_(std::move(texture)),
        map_(plane_to_texel),
        min_(min),
        max_(max),
        margin_(margin),
        viewer_z_(viewer_z) {}
  double Albedo(double x, double y) const override {
    if (x < min_.x() - margin_ || y < min_.y() - margin_ || x > max_.x() + margin_ ||
        y > max_.y() + margin_)
      return -1.0;
    const Eigen::Vector2d t = map_ * Eigen::Vector3d(x, y, 1.0);
    const int u = static_cast<int>(std::floor(t.x())), v = static_cast<int>(std::floor(t.y()));
    if (u < 0 || v < 0 || u >= texture_.cols || v >= texture_.rows) return 1.0;  // margin
    return texture_.at<uint8_t>(v, u) / 255.0;
  }
  Eigen::Vector2d Min() const override { return min_.array() - margin_; }
  Eigen::Vector2d Max() const override { return max_.array() + margin_; }
  double ViewerZ() const override { return viewer_z_; }

 private:
  cv::Mat texture_;
  Eigen::Matrix<double, 2, 3> map_;
  Eigen::Vector2d min_, max_;
  double margin_;
  double viewer_z_;
};

// OpenCV's own drawing of a ChArUco board. The drawing maps the board linearly onto the texture
// (x to the right; y down or up depending on the OpenCV version): both candidates are checked
// against the corners found in the drawing, and the map that fits is used. (The corners that
// interpolateCornersCharuco reports in the drawing sit on the texel edges, not half a texel
// before them, so they decide the orientation but do not set the offset.)
std::shared_ptr<PlanarPrint> MakeCharucoPrint(const BoardPattern& p) {
  const int per_square = 100, margin = per_square / 2;
  const int width = p.cols * per_square + 2 * margin, height = p.rows * per_square + 2 * margin;
  cv::Mat texture;
  p.charuco->draw(cv::Size(width, height), texture, margin, 1);
  std::vector<std::vector<cv::Point2f>> marker_corners;
  std::vector<int> marker_ids;
  cv::aruco::detectMarkers(texture, p.aruco_dictionary, marker_corners, marker_ids);
  std::vector<cv::Point2f> corners;
  std::vector<int> ids;
  cv::aruco::interpolateCornersCharuco(marker_corners, marker_ids, texture, p.charuco, corners,
                                       ids);
  if (ids.size() < 4) throw std::runtime_error("charuco: cannot read back OpenCV's own drawing");
  const double scale = per_square / p.square;  // texels per m
  Eigen::Matrix<double, 2, 3> down, up;
  down << scale, 0, margin, 0, scale, margin;
  up << scale, 0, margin, 0, -scale, height - margin;
  double err_down = 0.0, err_up = 0.0;
  for (size_t i = 0; i < ids.size(); ++i) {
    const Eigen::Vector3d x(p.points[ids[i]].x(), p.points[ids[i]].y(), 1.0);
    const Eigen::Vector2d c(corners[i].x, corners[i].y);
    err_down = std::max(err_down, (down * x - c).norm());
    err_up = std::max(err_up, (up * x - c).norm());
  }
  if (std::min(err_down, err_up) > 1.0)
    throw std::runtime_error("charuco: OpenCV's drawing does not map linearly onto the board");
  // Margin: half a square of white around the board (the texture's own margin is white too).
  return std::make_shared<TexturePrint>(texture, err_down < err_up ? down : up, p.extent_min,
                                        p.extent_max, 0.5 * p.square, p.viewer_z);
}

// One ArUco marker in its own frame: origin at its top-left corner, x to the top-right one, y to
// the bottom-left one; a white margin of a quarter of its size.
std::shared_ptr<PlanarPrint> MakeMarkerPrint(const cv::aruco::Dictionary& dictionary, int id,
                                             double size) {
  const int side = (dictionary.markerSize + 2) * 20;
  cv::Mat texture;
  dictionary.drawMarker(id, side, texture, 1);
  Eigen::Matrix<double, 2, 3> map;
  map << side / size, 0, 0, 0, side / size, 0;
  return std::make_shared<TexturePrint>(texture, map, Eigen::Vector2d::Zero(),
                                        Eigen::Vector2d(size, size), 0.25 * size, -1.0);
}

// Projects x (camera frame); NaN when behind.
Eigen::Vector2d ToPixel(const CameraIntrinsics& k, const Eigen::Vector3d& p) {
  return Project(k, p);
}

}  // namespace

std::vector<TargetPrint> MakeTargetPrints(const CalibrationTarget& target) {
  std::vector<TargetPrint> prints;
  for (const TargetFace& face : target.faces) {
    const BoardPattern& p = face.pattern;
    switch (p.type) {
      case PatternType::kChessboard:
        prints.push_back({std::make_shared<ChessboardPrint>(p), face.target_from_face});
        break;
      case PatternType::kCharuco:
        prints.push_back({MakeCharucoPrint(p), face.target_from_face});
        break;
      case PatternType::kMarkers:
        for (size_t m = 0; 4 * m + 3 < p.points.size(); ++m) {
          if (!p.points[4 * m].allFinite()) continue;
          const Eigen::Vector3d tl = p.points[4 * m], tr = p.points[4 * m + 1],
                                bl = p.points[4 * m + 3];
          const double size = (tr - tl).norm();
          const Eigen::Vector3d x = (tr - tl).normalized();
          Eigen::Vector3d y = bl - tl;
          y = (y - y.dot(x) * x).normalized();
          Eigen::Matrix3d r;
          r << x, y, x.cross(y);
          prints.push_back({MakeMarkerPrint(*p.aruco_dictionary, static_cast<int>(m), size),
                            face.target_from_face * Rigid3d(r, tl)});
        }
        break;
    }
  }
  return prints;
}

CameraRays::CameraRays(const CameraIntrinsics& intrinsics) : intrinsics_(intrinsics) {
  const int w = intrinsics.width + 1, h = intrinsics.height + 1;
  corners_.create(h, w, CV_32FC2);
  // Newton undistortion of every pixel corner, rows split over two threads.
  auto work = [&](int row_begin, int row_end) {
    for (int v = row_begin; v < row_end; ++v)
      for (int u = 0; u < w; ++u) {
        const Eigen::Vector2d ray = UndistortPoint(intrinsics_, Eigen::Vector2d(u - 0.5, v - 0.5));
        corners_.at<cv::Vec2f>(v, u) =
            cv::Vec2f(static_cast<float>(ray.x()), static_cast<float>(ray.y()));
      }
  };
  std::thread other(work, 0, h / 2);
  work(h / 2, h);
  other.join();
}

cv::Mat RenderPrints(const CameraRays& rays, const std::vector<PrintPose>& prints,
                     const RenderOptions& options) {
  const CameraIntrinsics& k = rays.intrinsics();
  const int w = k.width, h = k.height;

  // Per print: the homography from normalised camera coordinates to the plane, and the pixel box.
  struct Prepared {
    const PlanarPrint* print;
    Eigen::Matrix3d cam_to_plane;
    int u0, v0, u1, v1;  // pixel-corner box, inclusive
  };
  std::vector<Prepared> prepared;
  for (const PrintPose& pp : prints) {
    const Eigen::Matrix3d r = pp.cam_from_print.RotationMatrix();
    const Eigen::Vector3d& t = pp.cam_from_print.translation;
    // Seen from behind: not drawn.
    const Eigen::Vector3d camera_in_print = pp.cam_from_print.Inverse().translation;
    if (camera_in_print.z() * pp.print->ViewerZ() <= 0.0) continue;
    Eigen::Matrix3d plane_to_cam;
    plane_to_cam << r.col(0), r.col(1), t;
    Prepared p{pp.print, plane_to_cam.inverse(), 0, 0, w, h};
    // Box of the projected outline, grown by 3 % of the image for distortion.
    const Eigen::Vector2d lo = pp.print->Min(), hi = pp.print->Max();
    double umin = 1e30, vmin = 1e30, umax = -1e30, vmax = -1e30;
    bool bounded = true;
    for (int c = 0; c < 4; ++c) {
      const Eigen::Vector3d corner((c & 1) ? hi.x() : lo.x(), (c & 2) ? hi.y() : lo.y(), 0.0);
      const Eigen::Vector2d px = ToPixel(k, pp.cam_from_print * corner);
      if (!px.allFinite()) {
        bounded = false;
        break;
      }
      umin = std::min(umin, px.x());
      umax = std::max(umax, px.x());
      vmin = std::min(vmin, px.y());
      vmax = std::max(vmax, px.y());
    }
    if (bounded) {
      const double grow = 0.03 * std::max(w, h);
      p.u0 = std::clamp(static_cast<int>(std::floor(umin - grow)), 0, w);
      p.u1 = std::clamp(static_cast<int>(std::ceil(umax + grow)) + 1, 0, w);
      p.v0 = std::clamp(static_cast<int>(std::floor(vmin - grow)), 0, h);
      p.v1 = std::clamp(static_cast<int>(std::ceil(vmax + grow)) + 1, 0, h);
      if (p.u0 >= p.u1 || p.v0 >= p.v1) continue;  // outside the image
    }
    prepared.push_back(p);
  }

  // Albedo of the nearest print along a ray (negative: background).
  auto shade = [&](const Eigen::Vector2d& ray, int u, int v) {
    double best_depth = std::numeric_limits<double>::infinity(), albedo = -1.0;
    for (const Prepared& p : prepared) {
      if (u < p.u0 || u > p.u1 || v < p.v0 || v > p.v1) continue;
      const Eigen::Vector3d q = p.cam_to_plane * Eigen::Vector3d(ray.x(), ray.y(), 1.0);
      if (q.z() <= 0.0) continue;  // the plane is behind the camera along this ray
      const double depth = 1.0 / q.z();
      if (depth >= best_depth) continue;
      const double a = p.print->Albedo(q.x() * depth, q.y() * depth);
      if (a < 0.0) continue;
      best_depth = depth;
      albedo = a;
    }
    return albedo;
  };

  // Albedo at every pixel corner.
  cv::Mat corner_albedo(h + 1, w + 1, CV_32F);
  for (int v = 0; v <= h; ++v)
    for (int u = 0; u <= w; ++u)
      corner_albedo.at<float>(v, u) = static_cast<float>(shade(rays.Corner(u, v), u, v));

  cv::Mat image(h, w, CV_8U);
  std::mt19937_64 rng(options.seed);
  std::normal_distribution<double> noise(0.0, 1.0);
  const int n = std::max(1, options.supersample);
  auto to_grey = [&](double a) {
    return a < 0.0 ? options.background : options.black + a * (options.white - options.black);
  };
  for (int v = 0; v < h; ++v) {
    for (int u = 0; u < w; ++u) {
      const float a00 = corner_albedo.at<float>(v, u), a10 = corner_albedo.at<float>(v, u + 1);
      const float a01 = corner_albedo.at<float>(v + 1, u),
                  a11 = corner_albedo.at<float>(v + 1, u + 1);
      double grey;
      if (a00 == a10 && a00 == a01 && a00 == a11) {
        grey = to_grey(a00);
      } else {
        // An edge crosses the pixel: area sampling on an n x n grid of bilinear rays.
        const Eigen::Vector2d r00 = rays.Corner(u, v), r10 = rays.Corner(u + 1, v);
        const Eigen::Vector2d r01 = rays.Corner(u, v + 1), r11 = rays.Corner(u + 1, v + 1);
        double sum = 0.0;
        for (int j = 0; j < n; ++j)
          for (int i = 0; i < n; ++i) {
            const double fx = (i + 0.5) / n, fy = (j + 0.5) / n;
            const Eigen::Vector2d ray =
                (1 - fy) * ((1 - fx) * r00 + fx * r10) + fy * ((1 - fx) * r01 + fx * r11);
            sum += to_grey(shade(ray, u, v));
          }
        grey = sum / (n * n);
      }
      if (options.noise_sigma > 0.0) grey += options.noise_sigma * noise(rng);
      image.at<uint8_t>(v, u) = cv::saturate_cast<uint8_t>(std::lround(grey));
    }
  }
  return image;
}

cv::Mat RenderTarget(const Camera& camera, const CameraRays& rays,
                     const std::vector<TargetPrint>& prints, const Rigid3d& world_from_target,
                     const RenderOptions& options) {
  std::vector<PrintPose> poses;
  for (const TargetPrint& p : prints)
    poses.push_back(
        {p.print.get(), camera.cam_from_world * world_from_target * p.target_from_print});
  return RenderPrints(rays, poses, options);
}

std::vector<FaceProjection> ProjectTarget(const Camera& camera, const CalibrationTarget& target,
                                          const Rigid3d& world_from_target, double margin_px) {
  std::vector<FaceProjection> out;
  const CameraIntrinsics& k = camera.intrinsics;
  for (size_t f = 0; f < target.faces.size(); ++f) {
    const TargetFace& face = target.faces[f];
    const Rigid3d cam_from_face = camera.cam_from_world * world_from_target * face.target_from_face;
    const Eigen::Vector3d camera_in_face = cam_from_face.Inverse().translation;
    FaceProjection proj;
    proj.face = static_cast<int>(f);
    for (size_t id = 0; id < face.pattern.points.size(); ++id) {
      const Eigen::Vector3d& x = face.pattern.points[id];
      if (!x.allFinite()) continue;
      if (face.pattern.planar()) {
        if (camera_in_face.z() * face.pattern.viewer_z <= 0.0) break;  // face seen from behind
      } else {
        // A marker corner: its marker must face the camera.
        const int m = static_cast<int>(id) / 4;
        const Eigen::Vector3d& tl = face.pattern.points[4 * m];
        const Eigen::Vector3d n =
            -(face.pattern.points[4 * m + 1] - tl).cross(face.pattern.points[4 * m + 3] - tl);
        if (n.dot(camera_in_face - tl) <= 0.0) continue;
      }
      const Eigen::Vector2d px = Project(k, cam_from_face * x);
      if (!px.allFinite() || px.x() < margin_px || px.y() < margin_px ||
          px.x() > k.width - 1 - margin_px || px.y() > k.height - 1 - margin_px)
        continue;
      proj.ids.push_back(static_cast<int>(id));
      proj.pixels.push_back(px);
    }
    if (!proj.ids.empty()) out.push_back(proj);
  }
  return out;
}

std::vector<Rigid3d> RandomTargetPoses(const Rig& rig, const CalibrationTarget& target,
                                       const std::vector<int>& must_see, int count,
                                       const Eigen::Vector3d& center, const Eigen::Vector3d& spread,
                                       const Eigen::Quaterniond& base, double max_tilt_rad,
                                       std::mt19937& rng, double margin_px) {
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  std::vector<Rigid3d> poses;
  int tries = 0;
  while (static_cast<int>(poses.size()) < count) {
    if (++tries > 20000 * count)
      throw std::runtime_error(
          "RandomTargetPoses: no pose that every camera sees; widen the "
          "search or shrink the target");
    Eigen::Vector3d axis(unit(rng), unit(rng), unit(rng));
    if (axis.norm() < 1e-6) continue;
    const double angle = max_tilt_rad * std::abs(unit(rng));
    const Eigen::Quaterniond tilt(Eigen::AngleAxisd(angle, axis.normalized()));
    const Eigen::Vector3d position =
        center + Eigen::Vector3d(unit(rng), unit(rng), unit(rng)).cwiseProduct(spread);
    const Rigid3d pose(base * tilt, position);
    bool ok = true;
    for (int c : must_see) {
      bool seen = false;
      for (const FaceProjection& fp : ProjectTarget(rig.cameras[c], target, pose, margin_px)) {
        size_t total = 0;
        for (const Eigen::Vector3d& x : target.faces[fp.face].pattern.points)
          total += x.allFinite();
        if (fp.ids.size() == total) seen = true;
      }
      ok = ok && seen;
    }
    if (ok) poses.push_back(pose);
  }
  return poses;
}

Eigen::Quaterniond FacingPlusX(const BoardPattern& pattern) {
  Eigen::Matrix3d r;
  r << Eigen::Vector3d(0, -1, 0), Eigen::Vector3d(0, 0, -1), Eigen::Vector3d(1, 0, 0);
  if (pattern.viewer_z > 0) {
    r.col(1) *= -1;
    r.col(2) *= -1;
  }
  return Eigen::Quaterniond(r);
}

}  // namespace netlab::calib
