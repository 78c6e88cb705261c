#include "app/gui/document/calibration_presenter.h"

#include <QStringList>
#include <algorithm>

namespace netlab::gui {

CalibrationPresenter::CalibrationPresenter(const calib::Rig* rig, std::string rig_path)
    : rig_(rig), rig_path_(std::move(rig_path)) {}

std::vector<RigCameraRow> CalibrationPresenter::Cameras() const {
  std::vector<RigCameraRow> rows;
  for (const calib::Camera& c : rig_->cameras) {
    const calib::CameraIntrinsics& in = c.intrinsics;
    rows.push_back({c.name, in.width, in.height, in.fx, in.fy, in.cx, in.cy, in.distortion[0],
                    in.distortion[1], c.Center(), c.ViewDirection()});
  }
  return rows;
}

std::vector<Baseline> CalibrationPresenter::Baselines() const {
  std::vector<Baseline> out;
  const int n = static_cast<int>(rig_->cameras.size());
  for (int a = 0; a < n; ++a)
    for (int b = a + 1; b < n; ++b)
      out.push_back({a, b, (rig_->cameras[a].Center() - rig_->cameras[b].Center()).norm()});
  std::sort(out.begin(), out.end(),
            [](const Baseline& x, const Baseline& y) { return x.length_m < y.length_m; });
  return out;
}

std::array<Eigen::Vector3d, 5> CalibrationPresenter::Frustum(int c, double depth_m) const {
  const calib::Camera& camera = rig_->cameras[c];
  const calib::CameraIntrinsics& in = camera.intrinsics;
  const calib::Rigid3d world_from_cam = camera.cam_from_world.Inverse();
  std::array<Eigen::Vector3d, 5> points;
  points[0] = camera.Center();
  const double us[] = {0, static_cast<double>(in.width), static_cast<double>(in.width), 0};
  const double vs[] = {0, 0, static_cast<double>(in.height), static_cast<double>(in.height)};
  for (int i = 0; i < 4; ++i) {
    const Eigen::Vector3d p_in_cam((us[i] - in.cx) / in.fx * depth_m,
                                   (vs[i] - in.cy) / in.fy * depth_m, depth_m);
    points[i + 1] = world_from_cam * p_in_cam;
  }
  return points;
}

QString CalibrationPresenter::Summary() const {
  QStringList baselines;
  for (const Baseline& b : Baselines())
    baselines << QString("%1–%2 %3 m")
                     .arg(QString::fromStdString(rig_->cameras[b.a].name),
                          QString::fromStdString(rig_->cameras[b.b].name))
                     .arg(b.length_m, 0, 'f', 3);
  return QString("%1: %2 cameras · baselines %3")
      .arg(QString::fromStdString(rig_path_))
      .arg(rig_->cameras.size())
      .arg(baselines.join(", "));
}

}  // namespace netlab::gui
