#pragma once
// The calibration room without a window: the project's calibrated rig as the room shows it. Per
// camera its image size, focal lengths, principal point, distortion, centre and viewing
// direction; the baselines between the cameras; and the geometry of a 3D sketch (each camera as
// a frustum, the world frame's axes), so that a camera placed wrongly is seen at once.
//
//   CalibrationPresenter calibration(&session.rig(), "rig.yaml");
//   calibration.Cameras();      // the table's rows
//   calibration.Frustum(c, 0.3);  // camera c's centre and its image corners 0.3 m in front

#include <Eigen/Core>
#include <QString>
#include <array>
#include <string>
#include <vector>

#include "calibration/rig.h"

namespace netlab::gui {

struct RigCameraRow {
  std::string name;
  int width = 0, height = 0;             // px
  double fx = 0, fy = 0, cx = 0, cy = 0;  // px
  double k1 = 0, k2 = 0;                 // the first radial distortion terms
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();     // world, m
  Eigen::Vector3d direction = Eigen::Vector3d::UnitZ();  // optical axis, world, unit
};

struct Baseline {
  int a = 0, b = 0;        // rig cameras
  double length_m = 0.0;   // between their centres
};

class CalibrationPresenter {
 public:
  // `rig` must outlive the presenter; `rig_path` is shown as where it comes from.
  CalibrationPresenter(const calib::Rig* rig, std::string rig_path);

  const calib::Rig& rig() const { return *rig_; }
  std::vector<RigCameraRow> Cameras() const;
  // Every pair of cameras, nearest first.
  std::vector<Baseline> Baselines() const;
  // Camera c's centre followed by its four image corners' rays at `depth_m` in front (world, m;
  // a pinhole: the lens distortion left out of a sketch).
  std::array<Eigen::Vector3d, 5> Frustum(int c, double depth_m) const;
  // The line above the table: the file, the cameras, the baselines.
  QString Summary() const;

 private:
  const calib::Rig* rig_;
  std::string rig_path_;
};

}  // namespace netlab::gui
