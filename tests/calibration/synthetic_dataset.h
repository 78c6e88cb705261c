#pragma once
// Synthetic calibration data for the tests: a target at random poses, rendered for every camera of
// a rig and detected, with the truth kept.

#include <random>
#include <vector>

#include "calibration/calibrate.h"
#include "calibration/detect.h"
#include "calibration/synthetic.h"

namespace netlab::calib::testing {

using calib::FacingPlusX;

struct Dataset {
  CalibrationInput input;
  std::vector<Rigid3d> world_from_target;  // truth per frame
};

// Renders `target` at `poses` for every camera in `rig` (noise in grey levels) and detects it.
inline Dataset Render(const Rig& rig, const CalibrationTarget& target,
                      const std::vector<Rigid3d>& poses, double noise_sigma, uint64_t seed) {
  Dataset d;
  d.world_from_target = poses;
  d.input.num_frames = static_cast<int>(poses.size());
  const auto prints = MakeTargetPrints(target);
  for (size_t c = 0; c < rig.cameras.size(); ++c) {
    const Camera& camera = rig.cameras[c];
    d.input.camera_names.push_back(camera.name);
    d.input.image_sizes.emplace_back(camera.intrinsics.width, camera.intrinsics.height);
    const CameraRays rays(camera.intrinsics);
    for (size_t f = 0; f < poses.size(); ++f) {
      RenderOptions options;
      options.noise_sigma = noise_sigma;
      options.seed = seed + 1000 * c + f;
      const cv::Mat image = RenderTarget(camera, rays, prints, poses[f], options);
      const PatternDetection found = DetectPattern(image, target.faces[0].pattern);
      if (!found.empty())
        d.input.observations.push_back(
            MakeObservation(static_cast<int>(c), static_cast<int>(f), found));
    }
  }
  return d;
}

// Error of the estimated rig against the truth, up to the choice of world frame: the worst
// rotation (rad) and translation (m) error of cam_c_from_cam_0 over the cameras.
struct RelativeError {
  double rotation_rad = 0.0;
  double translation_m = 0.0;
};
inline RelativeError CompareRelativePoses(const Rig& estimate, const Rig& truth) {
  RelativeError e;
  const Rigid3d est0 = estimate.cameras[0].cam_from_world.Inverse();
  const Rigid3d true0 = truth.cameras[0].cam_from_world.Inverse();
  for (size_t c = 1; c < truth.cameras.size(); ++c) {
    const Rigid3d est = estimate.cameras[c].cam_from_world * est0;
    const Rigid3d tru = truth.cameras[c].cam_from_world * true0;
    e.rotation_rad = std::max(e.rotation_rad, est.rotation.angularDistance(tru.rotation));
    e.translation_m = std::max(e.translation_m, (est.translation - tru.translation).norm());
  }
  return e;
}

}  // namespace netlab::calib::testing
