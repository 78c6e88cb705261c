#include "calibration/calibrate.h"

#include <ceres/ceres.h>

#include <Eigen/Dense>
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <iomanip>
#include <mutex>
#include <numeric>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <set>
#include <sstream>
#include <stdexcept>
#include <thread>

#include "calibration/cost_functions.h"
#include "calibration/detect.h"

namespace netlab::calib {
namespace {

[[noreturn]] void Fail(const std::string& message) { throw std::runtime_error(message); }

Rigid3d FromRvecTvec(const cv::Vec3d& rvec, const cv::Vec3d& tvec) {
  cv::Mat r;
  cv::Rodrigues(rvec, r);
  Eigen::Matrix3d rotation;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) rotation(i, j) = r.at<double>(i, j);
  return Rigid3d(rotation, Eigen::Vector3d(tvec[0], tvec[1], tvec[2]));
}

// Mean of rigid transforms: quaternions aligned to the first and averaged, translations averaged.
Rigid3d AveragePoses(const std::vector<Rigid3d>& poses) {
  Eigen::Vector4d q = Eigen::Vector4d::Zero();
  Eigen::Vector3d t = Eigen::Vector3d::Zero();
  const Eigen::Vector4d first = poses.front().rotation.coeffs();
  for (const Rigid3d& p : poses) {
    Eigen::Vector4d c = p.rotation.coeffs();
    if (c.dot(first) < 0.0) c = -c;
    q += c;
    t += p.translation;
  }
  Eigen::Quaterniond mean(q.normalized());
  return Rigid3d(mean, t / static_cast<double>(poses.size()));
}

// Spread of a set of poses: RMS rotation angle (rad) from their mean plus RMS translation
// deviation divided by `length` (m).
double PoseDispersion(const std::vector<Rigid3d>& poses, double length) {
  const Rigid3d mean = AveragePoses(poses);
  double sum = 0.0;
  for (const Rigid3d& p : poses) {
    const double angle = p.rotation.angularDistance(mean.rotation);
    const double shift = (p.translation - mean.translation).norm() / length;
    sum += angle * angle + shift * shift;
  }
  return std::sqrt(sum / poses.size());
}

std::vector<cv::Point3f> ObjectPoints(const BoardPattern& pattern, const Observation& o) {
  std::vector<cv::Point3f> points;
  for (int id : o.ids) {
    const Eigen::Vector3d& x = pattern.points[id];
    points.emplace_back(static_cast<float>(x.x()), static_cast<float>(x.y()),
                        static_cast<float>(x.z()));
  }
  return points;
}

std::vector<cv::Point2f> ImagePoints(const Observation& o) {
  std::vector<cv::Point2f> points;
  for (const Eigen::Vector2d& p : o.pixels)
    points.emplace_back(static_cast<float>(p.x()), static_cast<float>(p.y()));
  return points;
}

// Linear triangulation (DLT) of one point from two calibrated views.
Eigen::Vector3d Triangulate(const Camera& a, const Eigen::Vector2d& pa, const Camera& b,
                            const Eigen::Vector2d& pb) {
  const Eigen::Vector2d xa = UndistortPoint(a.intrinsics, pa);
  const Eigen::Vector2d xb = UndistortPoint(b.intrinsics, pb);
  Eigen::Matrix<double, 3, 4> pa_m, pb_m;
  pa_m << a.cam_from_world.RotationMatrix(), a.cam_from_world.translation;
  pb_m << b.cam_from_world.RotationMatrix(), b.cam_from_world.translation;
  Eigen::Matrix4d m;
  m.row(0) = xa.x() * pa_m.row(2) - pa_m.row(0);
  m.row(1) = xa.y() * pa_m.row(2) - pa_m.row(1);
  m.row(2) = xb.x() * pb_m.row(2) - pb_m.row(0);
  m.row(3) = xb.y() * pb_m.row(2) - pb_m.row(1);
  const Eigen::Vector4d h = Eigen::JacobiSVD<Eigen::Matrix4d>(m, Eigen::ComputeFullV).matrixV().col(3);
  return h.head<3>() / h.w();
}

std::string Percent(double x) {
  std::ostringstream os;
  os << std::fixed << std::setprecision(0) << 100.0 * x << " %";
  return os.str();
}

}  // namespace

bool CalibrationOptions::IsValid(std::string* error) const {
  auto fail = [&](const char* message) {
    if (error) *error = message;
    return false;
  };
  if (!(huber_px > 0.0)) return fail("huber_px must be > 0");
  if (!(outlier_px > 0.0)) return fail("outlier_px must be > 0");
  if (min_views < 1) return fail("min_views must be >= 1");
  if (max_iterations < 1) return fail("max_iterations must be >= 1");
  return true;
}

std::string CalibrationSummary::BriefReport() const {
  std::ostringstream os;
  os << std::setprecision(4);
  os << "calibration: RMS " << rms_px << " px over " << observations << " points ("
     << outliers << " outliers dropped)\n";
  for (const CameraReport& c : cameras) {
    os << "  " << c.name << ": RMS " << c.rms_px << " px, " << c.views << " views, "
       << c.points << " points, coverage " << Percent(c.coverage);
    if (c.position_sigma_m > 0.0) os << ", centre sigma " << c.position_sigma_m * 1e3 << " mm";
    // The images that fit worst: where a bad detection would show.
    std::vector<std::pair<int, double>> worst = c.image_rms_px;
    std::sort(worst.begin(), worst.end(),
              [](const auto& a, const auto& b) { return a.second > b.second; });
    if (!worst.empty()) {
      os << "; worst images:";
      for (size_t i = 0; i < std::min<size_t>(3, worst.size()); ++i)
        os << " frame " << worst[i].first << " (" << worst[i].second << " px)";
    }
    os << "\n";
  }
  for (const PairCheck& p : pairs) {
    os << "  " << p.a << "-" << p.b << ": baseline " << p.baseline_m << " m";
    if (p.segments > 0)
      os << "; " << p.segments << " triangulated squares: " << p.mean_length_mm << " mm (nominal "
         << p.nominal_length_mm << " mm, RMS error " << p.rms_error_mm << " mm)";
    os << "\n";
  }
  for (const std::string& w : warnings) os << "  warning: " << w << "\n";
  return os.str();
}

CalibrationResult CalibrateRig(const CalibrationTarget& target, const CalibrationInput& input,
                               const CalibrationOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  std::string error;
  if (!options.IsValid(&error)) Fail("calibration options: " + error);
  const int num_cameras = static_cast<int>(input.camera_names.size());
  const int num_frames = input.num_frames;
  if (num_cameras == 0) Fail("calibration: no cameras");
  const bool marker_map = target.kind == CalibrationTarget::Kind::kMarkerMap;
  const bool foil = target.kind == CalibrationTarget::Kind::kDoubleSidedFoil;
  const BoardPattern& pattern = target.faces[0].pattern;
  CalibrationSummary summary;

  std::vector<Observation> obs;
  for (const Observation& o : input.observations)
    if (o.ids.size() >= 4) obs.push_back(o);
  std::vector<std::vector<int>> of_camera(num_cameras);
  for (size_t i = 0; i < obs.size(); ++i) of_camera[obs[i].camera].push_back(static_cast<int>(i));
  for (int c = 0; c < num_cameras; ++c)
    if (of_camera[c].empty())
      Fail("camera " + input.camera_names[c] + ": the target was not found in any of its views");

  // 1. Intrinsics: given, or Zhang's method on the camera's own planar views.
  std::vector<CameraIntrinsics> intrinsics(num_cameras);
  for (int c = 0; c < num_cameras; ++c) {
    const std::string& name = input.camera_names[c];
    const cv::Size size = input.image_sizes[c];
    const auto fixed = options.fixed_intrinsics.find(name);
    if (fixed != options.fixed_intrinsics.end()) {
      intrinsics[c] = fixed->second;
      if (intrinsics[c].width != size.width || intrinsics[c].height != size.height)
        Fail("camera " + name + ": the fixed intrinsics are for " +
             std::to_string(intrinsics[c].width) + "x" + std::to_string(intrinsics[c].height) +
             " images, its images are " + std::to_string(size.width) + "x" +
             std::to_string(size.height));
      continue;
    }
    if (!pattern.planar())
      Fail("camera " + name + ": a marker map does not constrain intrinsics; give them with "
           "--fix-intrinsics");
    if (of_camera[c].size() < 3)
      Fail("camera " + name + ": only " + std::to_string(of_camera[c].size()) +
           " views; estimating intrinsics needs at least 3 (or give them with --fix-intrinsics)");
    // An initial guess only (the bundle adjustment refines it with every view): at most 12
    // evenly spaced views, as OpenCV's dense solver grows with the cube of the views (0.54 s per
    // camera at 40 views).
    std::vector<std::vector<cv::Point3f>> object;
    std::vector<std::vector<cv::Point2f>> image;
    const size_t views = of_camera[c].size(), used = std::min<size_t>(views, 12);
    for (size_t k = 0; k < used; ++k) {
      const int i = of_camera[c][k * views / used];
      object.push_back(ObjectPoints(pattern, obs[i]));
      image.push_back(ImagePoints(obs[i]));
    }
    cv::Mat k, d;
    std::vector<cv::Mat> rvecs, tvecs;
    const int flags = options.rational ? cv::CALIB_RATIONAL_MODEL : 0;
    cv::calibrateCamera(object, image, size, k, d, rvecs, tvecs, flags);
    CameraIntrinsics& in = intrinsics[c];
    in.width = size.width;
    in.height = size.height;
    in.fx = k.at<double>(0, 0);
    in.fy = k.at<double>(1, 1);
    in.cx = k.at<double>(0, 2);
    in.cy = k.at<double>(1, 2);
    in.rational = options.rational;
    in.distortion.fill(0.0);
    for (int i = 0; i < std::min<int>(in.num_distortion(), d.total()); ++i)
      in.distortion[i] = d.at<double>(i);
  }

  // 2. Pose of each view's face in its camera.
  std::vector<Rigid3d> cam_from_face(obs.size());
  std::vector<bool> posed(obs.size(), false);
  for (size_t i = 0; i < obs.size(); ++i) {
    const CameraIntrinsics& in = intrinsics[obs[i].camera];
    cv::Vec3d rvec, tvec;
    const auto object = ObjectPoints(pattern, obs[i]);
    const auto image = ImagePoints(obs[i]);
    bool ok;
    if (pattern.planar()) {
      ok = cv::solvePnP(object, image, in.CameraMatrix(), in.DistortionCoefficients(), rvec, tvec,
                        false, cv::SOLVEPNP_IPPE);
    } else {
      ok = object.size() >= 6 && cv::solvePnP(object, image, in.CameraMatrix(),
                                               in.DistortionCoefficients(), rvec, tvec, false,
                                               cv::SOLVEPNP_SQPNP);
    }
    if (!ok) continue;
    cv::solvePnPRefineLM(object, image, in.CameraMatrix(), in.DistortionCoefficients(), rvec, tvec);
    cam_from_face[i] = FromRvecTvec(rvec, tvec);
    posed[i] = true;
  }

  // The reference camera: the one with the most views.
  int reference = 0;
  for (int c = 1; c < num_cameras; ++c)
    if (of_camera[c].size() > of_camera[reference].size()) reference = c;

  // 3. Which face each camera sees.
  std::vector<int> face_of_camera(num_cameras, 0);
  if (foil && !target.back_cameras.empty()) {
    for (const std::string& name : target.back_cameras) {
      const auto it = std::find(input.camera_names.begin(), input.camera_names.end(), name);
      if (it == input.camera_names.end())
        Fail("foil: back_cameras names '" + name + "', which is not one of the cameras");
      face_of_camera[it - input.camera_names.begin()] = 1;
    }
  } else if (foil) {
    // Relative parity by consistency: for each unassigned camera b and assigned camera a sharing
    // at least two frames, the hypothesis (same side or not) under which a_from_b stays the same
    // over those frames wins.
    const double length = (pattern.extent_max - pattern.extent_min).norm();
    std::vector<bool> assigned(num_cameras, false);
    assigned[reference] = true;
    bool progress = true;
    while (progress) {
      progress = false;
      for (int b = 0; b < num_cameras; ++b) {
        if (assigned[b]) continue;
        for (int a = 0; a < num_cameras && !assigned[b]; ++a) {
          if (!assigned[a]) continue;
          std::vector<std::pair<int, int>> shared;  // (obs of a, obs of b) in the same frame
          for (int ia : of_camera[a])
            for (int ib : of_camera[b])
              if (obs[ia].frame == obs[ib].frame && posed[ia] && posed[ib]) shared.emplace_back(ia, ib);
          if (shared.empty()) continue;
          double best = 1e300;
          int best_face = face_of_camera[a];
          for (int face_b : {0, 1}) {
            std::vector<Rigid3d> relative;
            for (const auto& [ia, ib] : shared) {
              const Rigid3d a_from_target =
                  cam_from_face[ia] * target.faces[face_of_camera[a]].target_from_face.Inverse();
              const Rigid3d b_from_target =
                  cam_from_face[ib] * target.faces[face_b].target_from_face.Inverse();
              relative.push_back(a_from_target * b_from_target.Inverse());
            }
            const double dispersion = PoseDispersion(relative, length);
            if (dispersion < best) {
              best = dispersion;
              best_face = face_b;
            }
          }
          if (shared.size() < 2)
            summary.warnings.push_back(
                "camera " + input.camera_names[b] + " shares one foil view with " +
                input.camera_names[a] + ": which side it sees is a guess (list it in the foil "
                "file's back_cameras if it sees the back)");
          face_of_camera[b] = best_face;
          assigned[b] = true;
          progress = true;
        }
      }
    }
  }
  for (Observation& o : obs) o.face = face_of_camera[o.camera];
  summary.face_of_camera = face_of_camera;

  // cam_from_target of a view.
  auto cam_from_target = [&](int i) {
    return cam_from_face[i] * target.faces[obs[i].face].target_from_face.Inverse();
  };

  // 4. Pose graph: from the reference camera over shared frames.
  std::vector<Rigid3d> cam_from_world(num_cameras);
  std::vector<bool> camera_known(num_cameras, false);
  std::vector<Rigid3d> world_from_target(std::max(num_frames, 1));
  std::vector<bool> frame_known(std::max(num_frames, 1), false);
  int gauge_frame = -1;
  if (marker_map) {
    // The map is the world and does not move: each camera from its own views.
    for (int c = 0; c < num_cameras; ++c) {
      std::vector<Rigid3d> estimates;
      for (int i : of_camera[c])
        if (posed[i]) estimates.push_back(cam_from_target(i));
      if (estimates.empty())
        Fail("camera " + input.camera_names[c] + ": no view with enough markers for a pose");
      cam_from_world[c] = AveragePoses(estimates);
      camera_known[c] = true;
    }
    std::fill(frame_known.begin(), frame_known.end(), true);
  } else {
    int first = -1;
    for (int i : of_camera[reference])
      if (posed[i] && (first < 0 || obs[i].frame < obs[first].frame)) first = i;
    gauge_frame = obs[first].frame;
    frame_known[gauge_frame] = true;
    cam_from_world[reference] = cam_from_target(first);
    camera_known[reference] = true;
    bool progress = true;
    while (progress) {
      progress = false;
      // Frames from known cameras (the view with the most points).
      for (int f = 0; f < num_frames; ++f) {
        if (frame_known[f]) continue;
        int best = -1;
        for (size_t i = 0; i < obs.size(); ++i)
          if (obs[i].frame == f && posed[i] && camera_known[obs[i].camera] &&
              (best < 0 || obs[i].ids.size() > obs[best].ids.size()))
            best = static_cast<int>(i);
        if (best < 0) continue;
        world_from_target[f] = cam_from_world[obs[best].camera].Inverse() * cam_from_target(best);
        frame_known[f] = true;
        progress = true;
      }
      // Cameras from known frames (averaged).
      for (int c = 0; c < num_cameras; ++c) {
        if (camera_known[c]) continue;
        std::vector<Rigid3d> estimates;
        for (int i : of_camera[c])
          if (posed[i] && frame_known[obs[i].frame])
            estimates.push_back(cam_from_target(i) * world_from_target[obs[i].frame].Inverse());
        if (estimates.empty()) continue;
        cam_from_world[c] = AveragePoses(estimates);
        camera_known[c] = true;
        progress = true;
      }
    }
    std::string lonely;
    for (int c = 0; c < num_cameras; ++c)
      if (!camera_known[c]) lonely += (lonely.empty() ? "" : ", ") + input.camera_names[c];
    if (!lonely.empty())
      Fail("camera(s) " + lonely + " share no frame with " + input.camera_names[reference] +
           " or the cameras linked to it: show the target to two cameras at the same time");
  }

  // 5. Bundle adjustment.
  std::vector<std::array<double, 4>> cam_q(num_cameras), frame_q(num_frames);
  std::vector<std::array<double, 3>> cam_t(num_cameras), frame_t(num_frames);
  std::vector<std::array<double, kNumIntrinsics>> cam_k(num_cameras);
  std::array<double, 4> map_q = {0, 0, 0, 1};
  std::array<double, 3> map_t = {0, 0, 0};
  for (int c = 0; c < num_cameras; ++c) {
    Eigen::Map<Eigen::Vector4d>(cam_q[c].data()) = cam_from_world[c].rotation.coeffs();
    Eigen::Map<Eigen::Vector3d>(cam_t[c].data()) = cam_from_world[c].translation;
    cam_k[c] = intrinsics[c].ToParameters();
  }
  for (int f = 0; f < num_frames; ++f) {
    Eigen::Map<Eigen::Vector4d>(frame_q[f].data()) = world_from_target[f].rotation.coeffs();
    Eigen::Map<Eigen::Vector3d>(frame_t[f].data()) = world_from_target[f].translation;
  }
  ceres::Problem problem;
  struct Residual {
    int obs, point;
    ceres::ResidualBlockId id;
  };
  std::vector<Residual> residuals;
  for (size_t i = 0; i < obs.size(); ++i) {
    const Observation& o = obs[i];
    if (!posed[i] || !frame_known[o.frame]) continue;
    double* tq = marker_map ? map_q.data() : frame_q[o.frame].data();
    double* tt = marker_map ? map_t.data() : frame_t[o.frame].data();
    const Rigid3d& target_from_face = target.faces[o.face].target_from_face;
    for (size_t k = 0; k < o.ids.size(); ++k) {
      const Eigen::Vector3d point = target_from_face * pattern.points[o.ids[k]];
      ceres::ResidualBlockId id = problem.AddResidualBlock(
          ReprojectionCostFunctor::Create(o.pixels[k], point),
          new ceres::HuberLoss(options.huber_px), cam_q[o.camera].data(), cam_t[o.camera].data(),
          cam_k[o.camera].data(), tq, tt);
      residuals.push_back({static_cast<int>(i), static_cast<int>(k), id});
    }
  }
  for (int c = 0; c < num_cameras; ++c) {
    problem.SetManifold(cam_q[c].data(), new ceres::EigenQuaternionManifold);
    const bool fixed = options.fixed_intrinsics.count(input.camera_names[c]) > 0;
    if (fixed || !options.refine_intrinsics) {
      problem.SetParameterBlockConstant(cam_k[c].data());
    } else if (!options.rational) {
      problem.SetManifold(cam_k[c].data(),
                          new ceres::SubsetManifold(kNumIntrinsics, {9, 10, 11}));
    }
  }
  if (marker_map) {
    problem.SetParameterBlockConstant(map_q.data());
    problem.SetParameterBlockConstant(map_t.data());
  } else {
    for (int f = 0; f < num_frames; ++f) {
      if (!problem.HasParameterBlock(frame_q[f].data())) continue;
      problem.SetManifold(frame_q[f].data(), new ceres::EigenQuaternionManifold);
    }
    // Gauge: the world is the target in the reference camera's first frame.
    problem.SetParameterBlockConstant(frame_q[gauge_frame].data());
    problem.SetParameterBlockConstant(frame_t[gauge_frame].data());
  }
  ceres::Solver::Options solver;
  solver.linear_solver_type = ceres::DENSE_SCHUR;
  solver.max_num_iterations = options.max_iterations;
  solver.num_threads = 2;
  solver.function_tolerance = 1e-12;
  solver.parameter_tolerance = 1e-12;
  ceres::Solver::Summary solver_summary;

  std::vector<bool> outlier(residuals.size(), false);
  auto residual_norm = [&](const Residual& r) {
    double res[2];
    double cost;
    problem.EvaluateResidualBlock(r.id, false, &cost, res, nullptr);
    return std::hypot(res[0], res[1]);
  };
  for (int round = 0; round < 3; ++round) {
    ceres::Solve(solver, &problem, &solver_summary);
    // Outliers: beyond max(outlier_px, 5 sigma), sigma from the median residual (Rayleigh).
    std::vector<double> norms;
    for (size_t r = 0; r < residuals.size(); ++r)
      if (!outlier[r]) norms.push_back(residual_norm(residuals[r]));
    if (norms.empty()) Fail("calibration: no observations left");
    std::vector<double> sorted = norms;
    std::nth_element(sorted.begin(), sorted.begin() + sorted.size() / 2, sorted.end());
    const double sigma = sorted[sorted.size() / 2] / 1.1774;
    const double threshold = std::max(options.outlier_px, 5.0 * sigma);
    int dropped = 0;
    for (size_t r = 0, n = 0; r < residuals.size(); ++r) {
      if (outlier[r]) continue;
      if (norms[n++] > threshold) {
        outlier[r] = true;
        problem.RemoveResidualBlock(residuals[r].id);
        ++dropped;
      }
    }
    if (dropped == 0) break;
  }

  // 6. Results and report.
  CalibrationResult result;
  for (int c = 0; c < num_cameras; ++c) {
    Camera camera;
    camera.name = input.camera_names[c];
    camera.intrinsics = intrinsics[c];
    camera.intrinsics.FromParameters(cam_k[c].data());
    camera.intrinsics.rational = options.fixed_intrinsics.count(camera.name)
                                     ? intrinsics[c].rational
                                     : options.rational;
    camera.cam_from_world = Rigid3d(Eigen::Quaterniond(cam_q[c][3], cam_q[c][0], cam_q[c][1],
                                                       cam_q[c][2]).normalized(),
                                    Eigen::Vector3d(cam_t[c][0], cam_t[c][1], cam_t[c][2]));
    result.rig.cameras.push_back(camera);
  }
  result.world_from_target.assign(num_frames, Rigid3d());
  result.frame_seen.assign(num_frames, false);
  for (int f = 0; f < num_frames && !marker_map; ++f) {
    if (!frame_known[f]) continue;
    result.world_from_target[f] =
        Rigid3d(Eigen::Quaterniond(frame_q[f][3], frame_q[f][0], frame_q[f][1], frame_q[f][2])
                    .normalized(),
                Eigen::Vector3d(frame_t[f][0], frame_t[f][1], frame_t[f][2]));
    result.frame_seen[f] = true;
  }

  // Residual statistics per camera and image; coverage.
  std::vector<double> sum_camera(num_cameras, 0.0);
  std::vector<int> count_camera(num_cameras, 0);
  std::map<std::pair<int, int>, std::pair<double, int>> per_image;
  std::vector<std::set<int>> cells(num_cameras);
  double sum_all = 0.0;
  int count_all = 0;
  for (size_t r = 0; r < residuals.size(); ++r) {
    const Observation& o = obs[residuals[r].obs];
    if (outlier[r]) {
      ++summary.outliers;
      continue;
    }
    const double n = residual_norm(residuals[r]);
    sum_camera[o.camera] += n * n;
    ++count_camera[o.camera];
    auto& image = per_image[{o.camera, o.frame}];
    image.first += n * n;
    ++image.second;
    sum_all += n * n;
    ++count_all;
    const Eigen::Vector2d& p = o.pixels[residuals[r].point];
    const cv::Size size = input.image_sizes[o.camera];
    const int cx = std::clamp(static_cast<int>(10.0 * p.x() / size.width), 0, 9);
    const int cy = std::clamp(static_cast<int>(10.0 * p.y() / size.height), 0, 9);
    cells[o.camera].insert(cy * 10 + cx);
  }
  summary.observations = count_all;
  summary.rms_px = count_all ? std::sqrt(sum_all / count_all) : 0.0;

  // Camera-centre uncertainty from the solver's covariance, scaled by the residual variance.
  const int num_params = problem.NumParameters() - 0;
  const double dof = std::max(1, 2 * count_all - num_params);
  const double variance = sum_all / dof;
  std::vector<double> centre_sigma(num_cameras, 0.0);
  {
    // The gauge is fixed, so the Jacobian has full rank and sparse QR applies (dense SVD took
    // 4 of the 5 s of a 4-camera, 40-view calibration).
    ceres::Covariance::Options cov_options;
    cov_options.algorithm_type = ceres::SPARSE_QR;
    cov_options.num_threads = 2;
    ceres::Covariance covariance(cov_options);
    std::vector<std::pair<const double*, const double*>> blocks;
    for (int c = 0; c < num_cameras; ++c) {
      blocks.emplace_back(cam_q[c].data(), cam_q[c].data());
      blocks.emplace_back(cam_q[c].data(), cam_t[c].data());
      blocks.emplace_back(cam_t[c].data(), cam_t[c].data());
    }
    if (covariance.Compute(blocks, &problem)) {
      for (int c = 0; c < num_cameras; ++c) {
        Eigen::Matrix<double, 3, 3, Eigen::RowMajor> qq, qt, tt;
        covariance.GetCovarianceBlockInTangentSpace(cam_q[c].data(), cam_q[c].data(), qq.data());
        covariance.GetCovarianceBlockInTangentSpace(cam_q[c].data(), cam_t[c].data(), qt.data());
        covariance.GetCovarianceBlockInTangentSpace(cam_t[c].data(), cam_t[c].data(), tt.data());
        // c = -R^T t; EigenQuaternionManifold perturbs on the left (R' = Exp(d) R), so
        // dc/dd = -R^T [t]x and dc/dt = -R^T.
        const Eigen::Matrix3d r = result.rig.cameras[c].cam_from_world.RotationMatrix();
        const Eigen::Vector3d t = result.rig.cameras[c].cam_from_world.translation;
        Eigen::Matrix3d tx;
        tx << 0, -t.z(), t.y(), t.z(), 0, -t.x(), -t.y(), t.x(), 0;
        const Eigen::Matrix3d jd = -r.transpose() * tx, jt = -r.transpose();
        const Eigen::Matrix3d cov = jd * qq * jd.transpose() + jd * qt * jt.transpose() +
                                    jt * qt.transpose() * jd.transpose() +
                                    jt * tt * jt.transpose();
        centre_sigma[c] = std::sqrt(std::max(0.0, variance * cov.trace()));
      }
    }
  }

  for (int c = 0; c < num_cameras; ++c) {
    CameraReport report;
    report.name = input.camera_names[c];
    report.points = count_camera[c];
    report.rms_px = count_camera[c] ? std::sqrt(sum_camera[c] / count_camera[c]) : 0.0;
    report.coverage = cells[c].size() / 100.0;
    report.position_sigma_m = centre_sigma[c];
    std::set<int> frames;
    for (const auto& [key, value] : per_image) {
      if (key.first != c) continue;
      report.image_rms_px.emplace_back(key.second, std::sqrt(value.first / value.second));
      frames.insert(key.second);
    }
    report.views = static_cast<int>(frames.size());
    summary.cameras.push_back(report);

    // Warnings on poor geometry.
    const bool estimated = !options.fixed_intrinsics.count(report.name);
    if (report.views < options.min_views)
      summary.warnings.push_back("camera " + report.name + ": only " +
                                 std::to_string(report.views) + " views (at least " +
                                 std::to_string(options.min_views) + " recommended)");
    if (estimated && pattern.planar()) {
      double spread = 0.0;
      for (int i : of_camera[c])
        for (int j : of_camera[c])
          if (posed[i] && posed[j])
            spread = std::max(spread, cam_from_face[i].rotation.angularDistance(
                                          cam_from_face[j].rotation));
      if (spread * 180.0 / M_PI < options.min_view_spread_deg)
        summary.warnings.push_back(
            "camera " + report.name + ": all views are alike (target turned by at most " +
            std::to_string(static_cast<int>(spread * 180.0 / M_PI)) +
            " deg between them): tilt it more, or focal length and distortion stay uncertain");
    }
    if (estimated && report.coverage < options.min_coverage)
      summary.warnings.push_back("camera " + report.name + ": points cover only " +
                                 Percent(report.coverage) +
                                 " of the image; distortion at its edges is extrapolated");
  }
  if (summary.outliers > 0)
    summary.warnings.push_back(std::to_string(summary.outliers) + " of " +
                               std::to_string(summary.outliers + summary.observations) +
                               " points dropped as outliers");

  // Baselines and the metric check: adjacent points triangulated by each pair of cameras that
  // sees the same face in the same frame.
  for (int a = 0; a < num_cameras; ++a) {
    for (int b = a + 1; b < num_cameras; ++b) {
      PairCheck pair;
      pair.a = input.camera_names[a];
      pair.b = input.camera_names[b];
      const Camera& ca = result.rig.cameras[a];
      const Camera& cb = result.rig.cameras[b];
      pair.baseline_m = (ca.Center() - cb.Center()).norm();
      double sum_length = 0.0, sum_error2 = 0.0, nominal_sum = 0.0;
      for (int ia : of_camera[a]) {
        for (int ib : of_camera[b]) {
          if (obs[ia].frame != obs[ib].frame || obs[ia].face != obs[ib].face) continue;
          std::map<int, Eigen::Vector3d> points;
          for (size_t k = 0; k < obs[ia].ids.size(); ++k)
            for (size_t l = 0; l < obs[ib].ids.size(); ++l)
              if (obs[ia].ids[k] == obs[ib].ids[l])
                points[obs[ia].ids[k]] = Triangulate(ca, obs[ia].pixels[k], cb, obs[ib].pixels[l]);
          for (const auto& [i, j] : pattern.neighbours) {
            const auto pi = points.find(i), pj = points.find(j);
            if (pi == points.end() || pj == points.end()) continue;
            const double length = (pi->second - pj->second).norm();
            const double nominal = (pattern.points[i] - pattern.points[j]).norm();
            sum_length += length;
            nominal_sum += nominal;
            sum_error2 += (length - nominal) * (length - nominal);
            ++pair.segments;
          }
        }
      }
      if (pair.segments > 0) {
        pair.mean_length_mm = 1e3 * sum_length / pair.segments;
        pair.nominal_length_mm = 1e3 * nominal_sum / pair.segments;
        pair.rms_error_mm = 1e3 * std::sqrt(sum_error2 / pair.segments);
      }
      summary.pairs.push_back(pair);
    }
  }
  summary.wall_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  result.summary = summary;
  return result;
}

CalibrationInput DetectInImages(const std::vector<std::string>& camera_names,
                                const std::vector<std::vector<std::string>>& files,
                                const CalibrationTarget& target,
                                const std::function<void(int, int)>& progress, int threads) {
  const int num_cameras = static_cast<int>(camera_names.size());
  if (num_cameras == 0 || files.size() != camera_names.size())
    Fail("calibration images: one image list per camera is needed");
  for (int c = 1; c < num_cameras; ++c)
    if (files[c].size() != files[0].size())
      Fail("unequal numbers of images per camera: " + camera_names[0] + " has " +
           std::to_string(files[0].size()) + ", " + camera_names[c] + " has " +
           std::to_string(files[c].size()) + " (images are matched by their sorted order)");
  const int num_frames = static_cast<int>(files[0].size());
  if (num_frames == 0) Fail("calibration images: no images");

  CalibrationInput input;
  input.camera_names = camera_names;
  input.image_names = files;
  input.num_frames = num_frames;
  input.image_sizes.assign(num_cameras, cv::Size());
  std::vector<std::vector<cv::Size>> sizes(num_cameras, std::vector<cv::Size>(num_frames));
  std::vector<std::vector<PatternDetection>> found(num_cameras,
                                                   std::vector<PatternDetection>(num_frames));
  const BoardPattern& pattern = target.faces[0].pattern;

  std::atomic<int> next{0}, done{0};
  std::mutex mutex;
  std::string first_error;
  const int total = num_cameras * num_frames;
  auto worker = [&] {
    while (true) {
      const int task = next++;
      if (task >= total) return;
      const int c = task / num_frames, f = task % num_frames;
      const std::string& file = files[c][f];
      cv::Mat image = cv::imread(file, cv::IMREAD_UNCHANGED);
      if (image.empty()) {
        std::lock_guard<std::mutex> lock(mutex);
        if (first_error.empty()) first_error = file + ": unreadable or not an image";
        continue;
      }
      sizes[c][f] = image.size();
      found[c][f] = DetectPattern(ToGray8(image), pattern);
      const int d = ++done;
      if (progress) {
        std::lock_guard<std::mutex> lock(mutex);
        progress(d, total);
      }
    }
  };
  std::vector<std::thread> pool;
  for (int t = 1; t < std::max(1, threads); ++t) pool.emplace_back(worker);
  worker();
  for (std::thread& t : pool) t.join();
  if (!first_error.empty()) Fail(first_error);

  for (int c = 0; c < num_cameras; ++c) {
    input.image_sizes[c] = sizes[c][0];
    for (int f = 1; f < num_frames; ++f)
      if (sizes[c][f] != sizes[c][0])
        Fail("camera " + camera_names[c] + ": " + files[c][f] + " is " +
             std::to_string(sizes[c][f].width) + "x" + std::to_string(sizes[c][f].height) +
             ", but " + files[c][0] + " is " + std::to_string(sizes[c][0].width) + "x" +
             std::to_string(sizes[c][0].height));
    int seen = 0;
    for (int f = 0; f < num_frames; ++f) {
      if (found[c][f].empty()) continue;
      ++seen;
      input.observations.push_back(MakeObservation(c, f, found[c][f]));
    }
    if (seen == 0) {
      std::string list;
      for (int f = 0; f < std::min(num_frames, 3); ++f) list += (f ? ", " : "") + files[c][f];
      if (num_frames > 3) list += ", ...";
      std::string what = target.description;
      if (pattern.type == PatternType::kChessboard)
        what = "chessboard of " + std::to_string(pattern.cols) + "x" +
               std::to_string(pattern.rows) + " inner corners";
      if (pattern.type == PatternType::kCharuco)
        what = "ChArUco board of " + std::to_string(pattern.cols) + "x" +
               std::to_string(pattern.rows) + " squares (" + pattern.dictionary + ")";
      Fail("no " + what + " found in any of the " + std::to_string(num_frames) + " images of " +
           camera_names[c] + " (" + list + "): check the board size and type");
    }
  }
  return input;
}

}  // namespace netlab::calib
