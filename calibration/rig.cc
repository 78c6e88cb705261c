#include "calibration/rig.h"

#include <cmath>
#include <filesystem>
#include <opencv2/core.hpp>
#include <opencv2/core/eigen.hpp>
#include <stdexcept>

#include "common/files.h"

namespace netlab::calib {

int Rig::Find(const std::string& name) const {
  for (size_t i = 0; i < cameras.size(); ++i)
    if (cameras[i].name == name) return static_cast<int>(i);
  return -1;
}

void WriteRig(const std::string& path, const Rig& rig) {
  // Written in memory, then through common/files.h's WriteTextFile: OpenCV's file writer does not
  // report a write that fails (a full disk), and would leave a truncated rig in place.
  cv::FileStorage fs(
      path, cv::FileStorage::WRITE | cv::FileStorage::MEMORY | cv::FileStorage::FORMAT_YAML);
  {
    fs << "cameras"
       << "[";
    for (const Camera& c : rig.cameras) {
      cv::Mat rotation, translation;
      cv::eigen2cv(Eigen::Matrix3d(c.cam_from_world.RotationMatrix()), rotation);
      cv::eigen2cv(Eigen::Vector3d(c.cam_from_world.translation), translation);
      fs << "{"
         << "name" << c.name << "image_width" << c.intrinsics.width << "image_height"
         << c.intrinsics.height << "camera_matrix" << c.intrinsics.CameraMatrix()
         << "distortion_coefficients" << c.intrinsics.DistortionCoefficients() << "rotation"
         << rotation << "translation" << translation << "}";
    }
    fs << "]";
  }
  WriteTextFile(path, fs.releaseAndGetString());
}

Rig ReadRig(const std::string& path) {
  if (!std::filesystem::exists(path)) throw std::runtime_error(path + ": rig file not found");
  // OpenCV's reader answers a folder with its own assertion ("buf in function 'open'").
  if (std::filesystem::is_directory(path))
    throw std::runtime_error(path + ": is a folder, not a rig file");
  cv::FileStorage fs;
  try {
    fs.open(path, cv::FileStorage::READ | cv::FileStorage::FORMAT_AUTO);
  } catch (const cv::Exception& e) {
    throw std::runtime_error(path + ": not a readable OpenCV YAML/XML file (" + e.msg + ")");
  }
  if (!fs.isOpened()) throw std::runtime_error(path + ": cannot open rig file");
  const cv::FileNode cameras = fs["cameras"];
  if (cameras.empty() || !cameras.isSeq())
    throw std::runtime_error(path + ": expected a sequence 'cameras'");
  Rig rig;
  int index = 0;
  for (const cv::FileNode& node : cameras) {
    Camera c;
    const std::string where = path + ": cameras[" + std::to_string(index++) + "]";
    auto fail = [&](const std::string& what) { throw std::runtime_error(where + ": " + what); };
    auto matrix = [&](const char* key, int rows, int cols_a, int cols_b = -1) {
      cv::Mat m;
      try {
        node[key] >> m;
      } catch (const cv::Exception&) {
        fail(std::string(key) + ": not a matrix");
      }
      if (m.empty()) fail(std::string("missing ") + key);
      if (m.rows != rows || (m.cols != cols_a && m.cols != cols_b))
        fail(std::string(key) + ": expected " + std::to_string(rows) + "x" +
             std::to_string(cols_a) +
             (cols_b > 0 ? " or " + std::to_string(rows) + "x" + std::to_string(cols_b)
                         : std::string()) +
             ", got " + std::to_string(m.rows) + "x" + std::to_string(m.cols));
      m.convertTo(m, CV_64F);
      return m;
    };
    if (node["name"].empty()) fail("missing name");
    node["name"] >> c.name;
    if (c.name.empty()) fail("empty name");
    const std::string where_named = where + " '" + c.name + "'";
    auto fail_named = [&](const std::string& what) {
      throw std::runtime_error(where_named + ": " + what);
    };
    if (node["image_width"].empty() || node["image_height"].empty())
      fail_named("missing image_width or image_height");
    node["image_width"] >> c.intrinsics.width;
    node["image_height"] >> c.intrinsics.height;
    const cv::Mat k = matrix("camera_matrix", 3, 3);
    c.intrinsics.fx = k.at<double>(0, 0);
    c.intrinsics.fy = k.at<double>(1, 1);
    c.intrinsics.cx = k.at<double>(0, 2);
    c.intrinsics.cy = k.at<double>(1, 2);
    const cv::Mat d = matrix("distortion_coefficients", 1, 5, 8);
    c.intrinsics.rational = d.cols == 8;
    for (int i = 0; i < d.cols; ++i) c.intrinsics.distortion[i] = d.at<double>(0, i);
    std::string error;
    if (!c.intrinsics.IsValid(&error)) fail_named(error);
    const cv::Mat r = matrix("rotation", 3, 3);
    cv::Mat t = matrix("translation", 3, 1, 3);
    Eigen::Matrix3d rotation;
    cv::cv2eigen(r, rotation);
    if (!((rotation.transpose() * rotation - Eigen::Matrix3d::Identity()).norm() < 1e-6) ||
        !(std::abs(rotation.determinant() - 1.0) < 1e-6))
      fail_named("rotation is not a rotation matrix (R^T R != I or det != 1)");
    t = t.reshape(1, 3);
    c.cam_from_world =
        Rigid3d(rotation, Eigen::Vector3d(t.at<double>(0), t.at<double>(1), t.at<double>(2)));
    if (rig.Find(c.name) >= 0) fail_named("camera name used twice");
    rig.cameras.push_back(c);
  }
  return rig;
}

Camera LookAtCamera(const std::string& name, const Eigen::Vector3d& center,
                    const Eigen::Vector3d& target, double focal_length_mm, double pixel_size_um,
                    int pixels) {
  Camera c;
  c.name = name;
  c.intrinsics.width = c.intrinsics.height = pixels;
  c.intrinsics.fx = c.intrinsics.fy = focal_length_mm * 1e3 / pixel_size_um;
  c.intrinsics.cx = c.intrinsics.cy = 0.5 * (pixels - 1);
  // OpenCV camera axes: z forward, x right, y down (world z is up).
  const Eigen::Vector3d z = (target - center).normalized();
  const Eigen::Vector3d x = z.cross(Eigen::Vector3d::UnitZ()).normalized();
  const Eigen::Vector3d y = z.cross(x);
  Eigen::Matrix3d world_from_cam;
  world_from_cam << x, y, z;
  c.cam_from_world = Rigid3d(world_from_cam, center).Inverse();
  return c;
}

Rig PaperRig(double scale) {
  const int pixels = static_cast<int>(std::lround(2048 * scale));
  const double pixel_size = 5.5 / scale;     // um: the same field of view at any scale
  const Eigen::Vector3d aim(1.0, 0.0, 0.0);  // middle of the flight path
  Rig rig;
  struct Placement {
    const char* name;
    Eigen::Vector3d center;
    double focal_mm;
    double k1, k2;
  };
  const Placement placements[] = {
      {"cam0", {-1.5, 0.5, 0.5}, 16.0, -0.08, 0.04},
      {"cam1", {-1.5, -0.5, 0.5}, 16.0, -0.08, 0.04},
      {"cam2", {4.0, -0.5, 0.5}, 25.0, -0.03, 0.01},
      {"cam3", {4.0, 0.5, 0.5}, 25.0, -0.03, 0.01},
  };
  for (const Placement& p : placements) {
    Camera c = LookAtCamera(p.name, p.center, aim, p.focal_mm, pixel_size, pixels);
    c.intrinsics.distortion[0] = p.k1;
    c.intrinsics.distortion[1] = p.k2;
    rig.cameras.push_back(c);
  }
  return rig;
}

}  // namespace netlab::calib
