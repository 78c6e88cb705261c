#include "calibration/rig_compare.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <stdexcept>
#include <string>

namespace netlab::calib {
namespace {

constexpr double kDeg = M_PI / 180.0;

// `rig` expressed in another world frame: cam_from_new = cam_from_old * old_from_new.
Rig MoveWorld(const Rig& rig, const Rigid3d& new_from_old) {
  Rig moved = rig;
  for (Camera& c : moved.cameras) c.cam_from_world = c.cam_from_world * new_from_old.Inverse();
  return moved;
}

// An arbitrary rigid motion of the world frame, far from the identity.
Rigid3d SomeMotion() {
  const Eigen::Vector3d axis = Eigen::Vector3d(0.3, -0.5, 0.8).normalized();
  return Rigid3d(Eigen::Quaterniond(Eigen::AngleAxisd(2.1, axis)), Eigen::Vector3d(3.1, -7.4, 0.9));
}

// `camera` turned by `angle_rad` about `axis_in_world` around its own centre, then moved by
// `shift` (world, m). Alone, its rotation error is `angle_rad` and its centre error |shift|.
Camera Perturbed(Camera camera, const Eigen::Vector3d& shift, const Eigen::Vector3d& axis_in_world,
                 double angle_rad) {
  const Rigid3d world_from_cam = camera.cam_from_world.Inverse();
  const Eigen::Quaterniond q(Eigen::AngleAxisd(angle_rad, axis_in_world.normalized()));
  camera.cam_from_world =
      Rigid3d(q * world_from_cam.rotation, world_from_cam.translation + shift).Inverse();
  return camera;
}

// Three cameras on one line (world x), all looking at the flight path.
Rig CollinearRig() {
  Rig rig;
  const double xs[] = {-2.0, -1.0, 4.0};
  for (int i = 0; i < 3; ++i)
    rig.cameras.push_back(LookAtCamera("cam" + std::to_string(i), Eigen::Vector3d(xs[i], 0.0, 0.5),
                                       Eigen::Vector3d(1.0, 0.4, 0.0), 16.0, 11.0, 1024));
  return rig;
}

void ExpectAllZero(const RigComparison& r, double tolerance) {
  for (const CameraComparison& c : r.cameras) {
    SCOPED_TRACE(c.name);
    EXPECT_NEAR(c.centre_error_m, 0.0, tolerance);
    EXPECT_NEAR(c.rotation_error_deg, 0.0, tolerance);
    for (double px : {c.fx_error_px, c.fy_error_px, c.cx_error_px, c.cy_error_px,
                      c.image_error_rms_px, c.image_error_max_px})
      EXPECT_EQ(px, 0.0);
  }
  EXPECT_NEAR(r.alignment_rms_m, 0.0, tolerance);
  EXPECT_NEAR(r.alignment_rms_deg, 0.0, tolerance);
  EXPECT_NEAR(r.scale_error, 0.0, tolerance);
}

std::string ErrorOf(const Rig& estimated, const Rig& truth) {
  try {
    CompareRigs(estimated, truth);
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "no error";
}

TEST(CompareRigs, IdenticalRigsHaveNoErrors) {
  const Rig rig = PaperRig();
  const RigComparison r = CompareRigs(rig, rig);
  ASSERT_EQ(r.cameras.size(), 4u);
  EXPECT_EQ(r.alignment, RigAlignment::kCentres);
  ExpectAllZero(r, 1e-12);
  EXPECT_NE(r.Report().find("cam3"), std::string::npos);
}

// The gauge does not matter: a rig expressed in any other world frame compares as equal, whichever
// alignment its geometry calls for, and the recovered transform is the motion undone.
TEST(CompareRigs, AMovedWorldFrameIsAlignedAway) {
  Rig two = PaperRig();
  two.cameras.resize(2);
  const struct {
    const char* what;
    Rig truth;
    RigAlignment alignment;
  } cases[] = {{"four cameras", PaperRig(), RigAlignment::kCentres},
               {"two cameras", two, RigAlignment::kMeanRotationAndCentroid},
               {"collinear cameras", CollinearRig(), RigAlignment::kMeanRotationAndCentroid}};
  const Rigid3d motion = SomeMotion();
  for (const auto& c : cases) {
    SCOPED_TRACE(c.what);
    const RigComparison r = CompareRigs(MoveWorld(c.truth, motion), c.truth);
    EXPECT_EQ(r.alignment, c.alignment);
    ExpectAllZero(r, 1e-9);
    const Rigid3d recovered = r.true_world_from_estimated_world * motion;  // identity
    EXPECT_LT(recovered.rotation.angularDistance(Eigen::Quaterniond::Identity()), 1e-12);
    EXPECT_LT(recovered.translation.norm(), 1e-9);
  }
}

// In one world frame (a marker-map calibration) nothing is aligned: a camera 2 mm off shows 2 mm,
// and a moved world frame shows the whole motion.
TEST(CompareRigs, OneWorldFrameComparesAsGiven) {
  const Rig truth = PaperRig();
  Rig moved = truth;
  Rigid3d world_from_cam = moved.cameras[2].cam_from_world.Inverse();
  world_from_cam.translation += Eigen::Vector3d(0.002, 0.0, 0.0);
  moved.cameras[2].cam_from_world = world_from_cam.Inverse();
  const RigComparison r = CompareRigs(moved, truth, /*same_world_frame=*/true);
  EXPECT_EQ(r.alignment, RigAlignment::kNone);
  EXPECT_NEAR(r.cameras[2].centre_error_m, 0.002, 1e-12);
  for (int c : {0, 1, 3}) EXPECT_LT(r.cameras[c].centre_error_m, 1e-12) << c;
  const RigComparison shifted = CompareRigs(MoveWorld(truth, SomeMotion()), truth, true);
  for (const auto& c : shifted.cameras) EXPECT_GT(c.centre_error_m, 0.1) << c.name;
}

// With four cameras the centre fit absorbs part of one camera's 2 mm displacement: the residual
// is (I - H) delta to first order, H the hat matrix of the linearised rigid fit (rotation w and
// translation t: c_i -> c_i + w x c_i + t). So the translation alone takes 1/4 of it, the rotation
// some more; the other cameras show the rest and turn by the fit's small rotation |w|.
TEST(CompareRigs, OneDisplacedAndTurnedCameraShowsItsErrors) {
  const Rig truth = PaperRig();
  const int moved = 2;
  const Eigen::Vector3d shift = 0.002 * Eigen::Vector3d(0.6, -0.48, 0.64);  // |shift| = 2 mm
  const Eigen::Vector3d axis = Eigen::Vector3d(0.2, 1.0, -0.3).normalized();
  const double angle = 0.1 * kDeg;
  Rig estimated = truth;
  estimated.cameras[moved] = Perturbed(truth.cameras[moved], shift, axis, angle);
  const RigComparison r = CompareRigs(MoveWorld(estimated, SomeMotion()), truth);
  ASSERT_EQ(r.alignment, RigAlignment::kCentres);

  // The first-order prediction: e = delta + A x, x = -(A^T A)^-1 A^T delta, A_i = [-[c_i]x, I].
  const int n = 4;
  Eigen::MatrixXd a(3 * n, 6);
  Eigen::VectorXd delta = Eigen::VectorXd::Zero(3 * n);
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d c = truth.cameras[i].Center();
    Eigen::Matrix3d cross;
    cross << 0, -c.z(), c.y(), c.z(), 0, -c.x(), -c.y(), c.x(), 0;
    a.block<3, 3>(3 * i, 0) = -cross;
    a.block<3, 3>(3 * i, 3) = Eigen::Matrix3d::Identity();
  }
  delta.segment<3>(3 * moved) = shift;
  const Eigen::VectorXd x = -(a.transpose() * a).ldlt().solve(a.transpose() * delta);
  const Eigen::VectorXd e = delta + a * x;
  const Eigen::Vector3d w = x.head<3>();
  // Neglected: second-order terms, of the order |w| |shift| ~ 1e-6 m for |w| ~ 7e-4 rad (measured:
  // 2e-7 m; and 6e-4 of the rotation errors).
  for (int i = 0; i < n; ++i) {
    SCOPED_TRACE(r.cameras[i].name);
    EXPECT_NEAR(r.cameras[i].centre_error_m, e.segment<3>(3 * i).norm(), 2e-6);
    EXPECT_LE(r.cameras[i].centre_error_m, r.cameras[moved].centre_error_m);
    const double expected_deg = (i == moved ? (angle * axis + w).norm() : w.norm()) / kDeg;
    EXPECT_NEAR(r.cameras[i].rotation_error_deg, expected_deg, 2e-3 * expected_deg);
    EXPECT_EQ(r.cameras[i].fx_error_px, 0.0);
    EXPECT_EQ(r.cameras[i].image_error_max_px, 0.0);
  }
  // The fit can only take away: (I - H) is a projection, so no camera shows more than the 2 mm.
  // (Measured: cam2 1.12 mm, the others 0.42-0.62 mm, all turned by |w| = 0.037 deg: the 1 m
  // width of the rig is a short lever for a displacement out of its plane.)
  EXPECT_LE(r.cameras[moved].centre_error_m, 0.002 + 1e-9);
  EXPECT_NEAR(r.alignment_rms_m, e.norm() / 2.0, 2e-6);  // sqrt(|e|^2 / 4)

  // Scale: to first order the baselines to the moved camera grow by their unit vectors . shift.
  double sum = 0.0, growth = 0.0;
  for (int i = 0; i < n; ++i)
    for (int j = i + 1; j < n; ++j)
      sum += (truth.cameras[i].Center() - truth.cameras[j].Center()).norm();
  for (int i = 0; i < n; ++i)
    if (i != moved)
      growth += (truth.cameras[moved].Center() - truth.cameras[i].Center()).normalized().dot(shift);
  EXPECT_NEAR(r.scale_error, growth / sum, 1e-6);
}

// Two cameras: the mean orientation splits a relative rotation evenly, and turning the baseline
// (1 m, across the turn's axis) by half the angle about the centroid moves each centre by
// 2 * 0.5 m * sin(angle / 4).
TEST(CompareRigs, TwoCamerasSplitARelativeRotation) {
  Rig truth = PaperRig();
  truth.cameras.resize(2);  // cam0, cam1: 1 m apart along world y
  const double angle = 0.1 * kDeg;
  Rig estimated = truth;
  estimated.cameras[1] =
      Perturbed(truth.cameras[1], Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitZ(), angle);
  const RigComparison r = CompareRigs(MoveWorld(estimated, SomeMotion()), truth);
  ASSERT_EQ(r.alignment, RigAlignment::kMeanRotationAndCentroid);
  for (const CameraComparison& c : r.cameras) {
    SCOPED_TRACE(c.name);
    EXPECT_NEAR(c.rotation_error_deg, 0.05, 1e-9);
    EXPECT_NEAR(c.centre_error_m, std::sin(angle / 4.0), 1e-12);
  }
  EXPECT_NEAR(r.scale_error, 0.0, 1e-12);
}

// A focal length 3 px too long maps the ray of pixel u to u + 3 (u - cx) / fx: the image error is
// largest at the image's left and right edges and its RMS follows from the documented grid.
TEST(CompareRigs, AFocalLengthErrorShowsInFxAndTheImage) {
  const Rig truth = PaperRig();
  Rig estimated = truth;
  estimated.cameras[0].intrinsics.fx += 3.0;
  const RigComparison r = CompareRigs(estimated, truth);
  const CameraIntrinsics& k = truth.cameras[0].intrinsics;
  const CameraComparison& c = r.cameras[0];
  EXPECT_NEAR(c.fx_error_px, 3.0, 1e-9);
  EXPECT_EQ(c.fy_error_px, 0.0);
  EXPECT_EQ(c.cx_error_px, 0.0);
  EXPECT_EQ(c.cy_error_px, 0.0);
  double sum_sq = 0.0;
  for (int j = 0; j < kImageGrid; ++j) {
    const double u = (k.width - 1) * double(j) / (kImageGrid - 1);
    sum_sq += std::pow(3.0 * (u - k.cx) / k.fx, 2);
  }
  EXPECT_NEAR(c.image_error_max_px, 3.0 * std::max(k.cx, k.width - 1 - k.cx) / k.fx, 1e-6);
  EXPECT_NEAR(c.image_error_rms_px, std::sqrt(sum_sq / kImageGrid), 1e-6);
  EXPECT_NEAR(c.image_error_max_px, 1.0555, 1e-3);  // 3 px * 1023.5 / 2909.1 px
  EXPECT_EQ(r.cameras[1].image_error_max_px, 0.0);
  EXPECT_NEAR(r.max_centre_error_m(), 0.0, 1e-12);
}

// A principal point off by (3, 4) px moves every pixel by 5 px; a distortion error moves the edges
// and leaves the principal point where it is, so it shows only in the image error.
TEST(CompareRigs, PrincipalPointAndDistortionErrorsShowInTheImage) {
  const Rig truth = PaperRig();
  Rig estimated = truth;
  estimated.cameras[1].intrinsics.cx += 3.0;
  estimated.cameras[1].intrinsics.cy += 4.0;
  estimated.cameras[2].intrinsics.distortion[0] += 0.01;  // k1
  const RigComparison r = CompareRigs(estimated, truth);
  EXPECT_NEAR(r.cameras[1].image_error_rms_px, 5.0, 1e-6);
  EXPECT_NEAR(r.cameras[1].image_error_max_px, 5.0, 1e-6);
  const CameraComparison& c = r.cameras[2];
  EXPECT_EQ(c.fx_error_px, 0.0);
  EXPECT_EQ(c.cx_error_px, 0.0);
  // Corner of cam2 (25 mm lens, 4545 px focal length): r^2 ~ 2 (1023.5 / 4545)^2 ~ 0.10, so
  // dk1 r^2 * (corner radius 1447 px) ~ 1.5 px at the corners, less inside.
  EXPECT_GT(c.image_error_max_px, 1.0);
  EXPECT_LT(c.image_error_max_px, 2.0);
  EXPECT_LT(c.image_error_rms_px, c.image_error_max_px);
}

TEST(CompareRigs, AMissingCameraIsNamed) {
  const Rig truth = PaperRig();
  Rig fewer = truth;
  fewer.cameras.erase(fewer.cameras.begin() + 1);  // no cam1
  std::string error = ErrorOf(truth, fewer);
  EXPECT_NE(error.find("'cam1' of the estimated rig is not in the true rig"), std::string::npos)
      << error;
  error = ErrorOf(fewer, truth);
  EXPECT_NE(error.find("'cam1' of the true rig is not in the estimated rig"), std::string::npos)
      << error;
  Rig resized = truth;
  resized.cameras[3].intrinsics.width = 1024;
  error = ErrorOf(resized, truth);
  EXPECT_NE(error.find("'cam3' has 1024x2048 pixels"), std::string::npos) << error;
  EXPECT_NE(ErrorOf(Rig(), truth).find("no cameras"), std::string::npos);
}

}  // namespace
}  // namespace netlab::calib
