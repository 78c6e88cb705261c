#pragma once
// Cameras in one world frame, and the rig file.
//
// rig.yaml is OpenCV FileStorage YAML (readable by cv::FileStorage and Python's cv2.FileStorage):
//   cameras:
//     - name: cam0
//       image_width: 2048
//       image_height: 2048
//       camera_matrix: !!opencv-matrix 3x3
//       distortion_coefficients: !!opencv-matrix 1x5 (or 1x8: rational model)
//       rotation: !!opencv-matrix 3x3      cam_from_world
//       translation: !!opencv-matrix 3x1   cam_from_world, m
// p_in_cam = rotation * p_in_world + translation.

#include <string>
#include <vector>

#include "calibration/camera.h"
#include "calibration/rigid3.h"

namespace netlab::calib {

struct Camera {
  std::string name;
  CameraIntrinsics intrinsics;
  Rigid3d cam_from_world;

  // Pixel of a world point (NaN behind the camera).
  Eigen::Vector2d ProjectWorld(const Eigen::Vector3d& p_in_world) const {
    return Project(intrinsics, cam_from_world * p_in_world);
  }
  // Projection centre in the world frame, m.
  Eigen::Vector3d Center() const { return cam_from_world.Inverse().translation; }
  // Unit viewing direction (optical axis) in the world frame.
  Eigen::Vector3d ViewDirection() const {
    return cam_from_world.rotation.conjugate() * Eigen::Vector3d::UnitZ();
  }
};

struct Rig {
  std::vector<Camera> cameras;

  int Find(const std::string& name) const;  // index, or -1
};

// Writes `rig` to `path` through "<path>.partial" and a rename. Throws std::runtime_error.
void WriteRig(const std::string& path, const Rig& rig);
// Reads a rig file; throws std::runtime_error naming the file, the camera and the field on
// missing fields, wrong matrix sizes, non-positive focal lengths or a rotation that is not one.
Rig ReadRig(const std::string& path);

// A camera at `center` (world, m) looking at `target`, image "up" towards world +z, with the
// pinhole of a lens of `focal_length_mm` on a square sensor of `pixels` of `pixel_size_um`.
Camera LookAtCamera(const std::string& name, const Eigen::Vector3d& center,
                    const Eigen::Vector3d& target, double focal_length_mm, double pixel_size_um,
                    int pixels);

// The paper's rig (sec. 5.1, Fig. 11): two stereo pairs facing each other along the net's flight
// axis (world x; the net flies from the ejector at the origin towards a target ~2 m away; z up),
// 0.5 m above it, 1 m stereo base, 5.5 m between the pairs; 16 mm lenses on cam0/cam1 (behind the
// ejector, looking +x) and 25 mm on cam2/cam3 (behind the target, looking -x); 2048 x 2048 pixels
// of 5.5 um; mild barrel distortion. `scale` < 1 shrinks the images (and focal lengths) for fast
// tests.
Rig PaperRig(double scale = 1.0);

}  // namespace netlab::calib
