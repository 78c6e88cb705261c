#include "calibration/calibrate.h"

#include <ceres/ceres.h>
#include <glob.h>

#include <Eigen/Dense>
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <limits>
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
#include "calibration/ray.h"

namespace netlab::calib {
namespace {

// A PNG or JPEG cut short (a copy that stopped, a full disk) lacks its end marker. Decoding one
// makes libpng print "libpng error: Read Error" on stderr ahead of netlab's own message; such a
// file is named here instead and never decoded. Other files go to the decoder as they are.
std::string TruncatedImage(const std::string& path) {
  std::ifstream in(path, std::ios::binary | std::ios::ate);
  if (!in) return "";
  const std::streamoff size = in.tellg();
  auto bytes = [&](std::streamoff at, int n) {
    std::string b(n, '\0');
    in.seekg(at);
    in.read(b.data(), n);
    return in ? b : std::string();
  };
  if (size >= 8 && bytes(0, 8) == "\x89PNG\r\n\x1a\n") {
    if (size < 20 || bytes(size - 8, 4) != "IEND")
      return "a truncated PNG (" + std::to_string(size) + " bytes, no IEND chunk at its end)";
  } else if (size >= 3 && bytes(0, 3) == "\xff\xd8\xff") {
    if (bytes(size - 2, 2) != "\xff\xd9")
      return "a truncated JPEG (" + std::to_string(size) + " bytes, no end-of-image marker)";
  }
  return "";
}

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
  Eigen::Matrix<double, 2, 4> ra, rb;
  if (!RayEquations(a, pa, &ra) || !RayEquations(b, pb, &rb))
    return Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());
  Eigen::Matrix4d m;
  m << ra, rb;
  const Eigen::Vector4d h =
      Eigen::JacobiSVD<Eigen::Matrix4d>(m, Eigen::ComputeFullV).matrixV().col(3);
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
  os << "calibration: RMS " << rms_px << " px over " << observations << " points (" << outliers
     << " outliers dropped)\n";
  for (const CameraReport& c : cameras) {
    os << "  " << c.name << ": RMS " << c.rms_px << " px, " << c.views << " views, " << c.points
       << " points, coverage " << Percent(c.coverage);
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

namespace {

// What CalibrateRig is given; fixed while it runs.
struct CalibrationSetup {
  CalibrationSetup(const CalibrationTarget& calibration_target,
                   const CalibrationInput& calibration_input,
                   const CalibrationOptions& calibration_options)
      : target(calibration_target),
        input(calibration_input),
        options(calibration_options),
        pattern(calibration_target.faces[0].pattern),
        num_cameras(static_cast<int>(calibration_input.camera_names.size())),
        num_frames(calibration_input.num_frames),
        marker_map(calibration_target.kind == CalibrationTarget::Kind::kMarkerMap),
        foil(calibration_target.kind == CalibrationTarget::Kind::kDoubleSidedFoil) {}

  const CalibrationTarget& target;
  const CalibrationInput& input;
  const CalibrationOptions& options;
  const BoardPattern& pattern;
  int num_cameras;
  int num_frames;
  bool marker_map;
  bool foil;
};

// What the stages of CalibrateRig compute before the bundle adjustment, in the order they
// compute it.
struct CalibrationState {
  // GatherDetections: the views with at least 4 points, and the indices of each camera's views.
  std::vector<Observation> obs;
  std::vector<std::vector<int>> of_camera;
  // InitializeIntrinsics: per camera.
  std::vector<CameraIntrinsics> intrinsics;
  // PoseViews: the pose of each view's face in its camera, where PnP succeeded (`posed`).
  std::vector<Rigid3d> cam_from_face;
  std::vector<bool> posed;
  // ChooseReferenceCamera: the camera with the most views.
  int reference = 0;
  // InitializePoses: every camera and frame reachable from the reference camera; the frame
  // that fixes the gauge (-1 for a marker map, whose frame is the world).
  std::vector<Rigid3d> cam_from_world;
  std::vector<bool> camera_known;
  std::vector<Rigid3d> world_from_target;
  std::vector<bool> frame_known;
  int gauge_frame = -1;
  // Filled by the stages as they go (AssignFaces: face_of_camera and warnings).
  CalibrationSummary summary;

  // cam_from_target of view `i`.
  Rigid3d CamFromTarget(const CalibrationTarget& target, int i) const {
    return cam_from_face[i] * target.faces[obs[i].face].target_from_face.Inverse();
  }
};

// Detections: the views with at least 4 points, grouped by camera; a camera without any is an
// error.
void GatherDetections(const CalibrationSetup& setup, CalibrationState& s) {
  for (const Observation& o : setup.input.observations)
    if (o.ids.size() >= 4) s.obs.push_back(o);
  s.of_camera.assign(setup.num_cameras, {});
  for (size_t i = 0; i < s.obs.size(); ++i)
    s.of_camera[s.obs[i].camera].push_back(static_cast<int>(i));
  for (int c = 0; c < setup.num_cameras; ++c)
    if (s.of_camera[c].empty())
      Fail("camera " + setup.input.camera_names[c] +
           ": the target was not found in any of its views");
}

// The fixed intrinsics of camera `c`, checked against its image size.
CameraIntrinsics CheckedFixedIntrinsics(const CalibrationSetup& setup, int c,
                                        const CameraIntrinsics& fixed) {
  const std::string& name = setup.input.camera_names[c];
  const cv::Size size = setup.input.image_sizes[c];
  if (fixed.width != size.width || fixed.height != size.height)
    Fail("camera " + name + ": the fixed intrinsics are for " + std::to_string(fixed.width) + "x" +
         std::to_string(fixed.height) + " images, its images are " + std::to_string(size.width) +
         "x" + std::to_string(size.height));
  return fixed;
}

// Zhang's method (cv::calibrateCamera) on camera `c`'s own planar views.
CameraIntrinsics ZhangIntrinsics(const CalibrationSetup& setup, const CalibrationState& s, int c) {
  const std::string& name = setup.input.camera_names[c];
  const cv::Size size = setup.input.image_sizes[c];
  const std::vector<int>& views_of_c = s.of_camera[c];
  if (!setup.pattern.planar())
    Fail("camera " + name +
         ": a marker map does not constrain intrinsics; give them with "
         "--fix-intrinsics");
  if (views_of_c.size() < 3)
    Fail("camera " + name + ": only " + std::to_string(views_of_c.size()) +
         " views; estimating intrinsics needs at least 3 (or give them with --fix-intrinsics)");
  // An initial guess only (the bundle adjustment refines it with every view): at most 12
  // evenly spaced views, as OpenCV's dense solver grows with the cube of the views (0.54 s per
  // camera at 40 views).
  std::vector<std::vector<cv::Point3f>> object;
  std::vector<std::vector<cv::Point2f>> image;
  const size_t views = views_of_c.size(), used = std::min<size_t>(views, 12);
  for (size_t k = 0; k < used; ++k) {
    const int i = views_of_c[k * views / used];
    object.push_back(ObjectPoints(setup.pattern, s.obs[i]));
    image.push_back(ImagePoints(s.obs[i]));
  }
  cv::Mat k, d;
  std::vector<cv::Mat> rvecs, tvecs;
  const int flags = setup.options.rational ? cv::CALIB_RATIONAL_MODEL : 0;
  cv::calibrateCamera(object, image, size, k, d, rvecs, tvecs, flags);
  // OpenCV's camera matrix and distortion vector -> our intrinsics.
  CameraIntrinsics in;
  in.width = size.width;
  in.height = size.height;
  in.fx = k.at<double>(0, 0);
  in.fy = k.at<double>(1, 1);
  in.cx = k.at<double>(0, 2);
  in.cy = k.at<double>(1, 2);
  in.rational = setup.options.rational;
  in.distortion.fill(0.0);
  for (int i = 0; i < std::min<int>(in.num_distortion(), d.total()); ++i)
    in.distortion[i] = d.at<double>(i);
  return in;
}

// 1. Intrinsics: given, or Zhang's method on the camera's own planar views.
void InitializeIntrinsics(const CalibrationSetup& setup, CalibrationState& s) {
  s.intrinsics.assign(setup.num_cameras, CameraIntrinsics());
  for (int c = 0; c < setup.num_cameras; ++c) {
    const auto fixed = setup.options.fixed_intrinsics.find(setup.input.camera_names[c]);
    s.intrinsics[c] = fixed != setup.options.fixed_intrinsics.end()
                          ? CheckedFixedIntrinsics(setup, c, fixed->second)
                          : ZhangIntrinsics(setup, s, c);
  }
}

// 2. Pose of each view's face in its camera: PnP (IPPE for a plane, SQPnP for a marker map with
// at least 6 points), refined by Levenberg-Marquardt.
void PoseViews(const CalibrationSetup& setup, CalibrationState& s) {
  s.cam_from_face.assign(s.obs.size(), Rigid3d());
  s.posed.assign(s.obs.size(), false);
  for (size_t i = 0; i < s.obs.size(); ++i) {
    const CameraIntrinsics& in = s.intrinsics[s.obs[i].camera];
    cv::Vec3d rvec, tvec;
    const auto object = ObjectPoints(setup.pattern, s.obs[i]);
    const auto image = ImagePoints(s.obs[i]);
    bool ok;
    if (setup.pattern.planar()) {
      ok = cv::solvePnP(object, image, in.CameraMatrix(), in.DistortionCoefficients(), rvec, tvec,
                        false, cv::SOLVEPNP_IPPE);
    } else {
      ok = object.size() >= 6 &&
           cv::solvePnP(object, image, in.CameraMatrix(), in.DistortionCoefficients(), rvec, tvec,
                        false, cv::SOLVEPNP_SQPNP);
    }
    if (!ok) continue;
    cv::solvePnPRefineLM(object, image, in.CameraMatrix(), in.DistortionCoefficients(), rvec, tvec);
    s.cam_from_face[i] = FromRvecTvec(rvec, tvec);
    s.posed[i] = true;
  }
}

// The reference camera: the one with the most views (the first of equals).
void ChooseReferenceCamera(const CalibrationSetup& setup, CalibrationState& s) {
  s.reference = 0;
  for (int c = 1; c < setup.num_cameras; ++c)
    if (s.of_camera[c].size() > s.of_camera[s.reference].size()) s.reference = c;
}

// The face camera `b` sees, given the face assigned camera `a` sees and the views of both in
// `shared` frames: the one under which a_from_b disperses least over those frames (`length`
// scales translations against angles).
int MostConsistentFace(const CalibrationSetup& setup, const CalibrationState& s, int face_a,
                       const std::vector<std::pair<int, int>>& shared, double length) {
  double best = 1e300;
  int best_face = face_a;
  for (int face_b : {0, 1}) {
    std::vector<Rigid3d> relative;
    for (const auto& [ia, ib] : shared) {
      const Rigid3d a_from_target =
          s.cam_from_face[ia] * setup.target.faces[face_a].target_from_face.Inverse();
      const Rigid3d b_from_target =
          s.cam_from_face[ib] * setup.target.faces[face_b].target_from_face.Inverse();
      relative.push_back(a_from_target * b_from_target.Inverse());
    }
    const double dispersion = PoseDispersion(relative, length);
    if (dispersion < best) {
      best = dispersion;
      best_face = face_b;
    }
  }
  return best_face;
}

// The posed views of cameras `a` and `b` in the same frame: (view of a, view of b).
std::vector<std::pair<int, int>> SharedPosedViews(const CalibrationState& s, int a, int b) {
  std::vector<std::pair<int, int>> shared;
  for (int ia : s.of_camera[a])
    for (int ib : s.of_camera[b])
      if (s.obs[ia].frame == s.obs[ib].frame && s.posed[ia] && s.posed[ib])
        shared.emplace_back(ia, ib);
  return shared;
}

// Relative parity by consistency: for each unassigned camera b and assigned camera a sharing
// at least two frames, the hypothesis (same side or not) under which a_from_b stays the same
// over those frames wins. Returns the face per camera; warns where one shared view decided it.
std::vector<int> FoilFacesByConsistency(const CalibrationSetup& setup, CalibrationState& s) {
  std::vector<int> face_of_camera(setup.num_cameras, 0);
  const double length = (setup.pattern.extent_max - setup.pattern.extent_min).norm();
  std::vector<bool> assigned(setup.num_cameras, false);
  assigned[s.reference] = true;
  bool progress = true;
  while (progress) {
    progress = false;
    for (int b = 0; b < setup.num_cameras; ++b) {
      if (assigned[b]) continue;
      for (int a = 0; a < setup.num_cameras && !assigned[b]; ++a) {
        if (!assigned[a]) continue;
        const std::vector<std::pair<int, int>> shared = SharedPosedViews(s, a, b);
        if (shared.empty()) continue;
        const int best_face = MostConsistentFace(setup, s, face_of_camera[a], shared, length);
        if (shared.size() < 2)
          s.summary.warnings.push_back("camera " + setup.input.camera_names[b] +
                                       " shares one foil view with " + setup.input.camera_names[a] +
                                       ": which side it sees is a guess (list it in the foil "
                                       "file's back_cameras if it sees the back)");
        face_of_camera[b] = best_face;
        assigned[b] = true;
        progress = true;
      }
    }
  }
  return face_of_camera;
}

// The faces the foil file's back_cameras name: 1 for those, 0 for the others.
std::vector<int> FoilFacesAsNamed(const CalibrationSetup& setup) {
  std::vector<int> face_of_camera(setup.num_cameras, 0);
  const std::vector<std::string>& names = setup.input.camera_names;
  for (const std::string& name : setup.target.back_cameras) {
    const auto it = std::find(names.begin(), names.end(), name);
    if (it == names.end())
      Fail("foil: back_cameras names '" + name + "', which is not one of the cameras");
    face_of_camera[it - names.begin()] = 1;
  }
  return face_of_camera;
}

// 3. Which face each camera sees (0 unless the target is a foil), set on every view.
void AssignFaces(const CalibrationSetup& setup, CalibrationState& s) {
  std::vector<int> face_of_camera(setup.num_cameras, 0);
  if (setup.foil && !setup.target.back_cameras.empty()) {
    face_of_camera = FoilFacesAsNamed(setup);
  } else if (setup.foil) {
    face_of_camera = FoilFacesByConsistency(setup, s);
  }
  for (Observation& o : s.obs) o.face = face_of_camera[o.camera];
  s.summary.face_of_camera = face_of_camera;
}

// The map is the world and does not move: each camera from its own views (averaged).
void PoseCamerasOnMarkerMap(const CalibrationSetup& setup, CalibrationState& s) {
  for (int c = 0; c < setup.num_cameras; ++c) {
    std::vector<Rigid3d> estimates;
    for (int i : s.of_camera[c])
      if (s.posed[i]) estimates.push_back(s.CamFromTarget(setup.target, i));
    if (estimates.empty())
      Fail("camera " + setup.input.camera_names[c] + ": no view with enough markers for a pose");
    s.cam_from_world[c] = AveragePoses(estimates);
    s.camera_known[c] = true;
  }
  std::fill(s.frame_known.begin(), s.frame_known.end(), true);
}

// One sweep of the pose graph: unknown frames from known cameras (the view with the most
// points), then unknown cameras from known frames (averaged). Returns whether anything new
// became known.
bool ExtendPoseGraph(const CalibrationSetup& setup, CalibrationState& s) {
  bool progress = false;
  // Frames from known cameras (the view with the most points).
  for (int f = 0; f < setup.num_frames; ++f) {
    if (s.frame_known[f]) continue;
    int best = -1;
    for (size_t i = 0; i < s.obs.size(); ++i)
      if (s.obs[i].frame == f && s.posed[i] && s.camera_known[s.obs[i].camera] &&
          (best < 0 || s.obs[i].ids.size() > s.obs[best].ids.size()))
        best = static_cast<int>(i);
    if (best < 0) continue;
    s.world_from_target[f] =
        s.cam_from_world[s.obs[best].camera].Inverse() * s.CamFromTarget(setup.target, best);
    s.frame_known[f] = true;
    progress = true;
  }
  // Cameras from known frames (averaged).
  for (int c = 0; c < setup.num_cameras; ++c) {
    if (s.camera_known[c]) continue;
    std::vector<Rigid3d> estimates;
    for (int i : s.of_camera[c])
      if (s.posed[i] && s.frame_known[s.obs[i].frame])
        estimates.push_back(s.CamFromTarget(setup.target, i) *
                            s.world_from_target[s.obs[i].frame].Inverse());
    if (estimates.empty()) continue;
    s.cam_from_world[c] = AveragePoses(estimates);
    s.camera_known[c] = true;
    progress = true;
  }
  return progress;
}

// A moving target: the world is the target in the reference camera's first posed frame; the
// pose graph grows from there over shared frames. A camera it never reaches is an error.
void ChainPosesFromReference(const CalibrationSetup& setup, CalibrationState& s) {
  int first = -1;
  for (int i : s.of_camera[s.reference])
    if (s.posed[i] && (first < 0 || s.obs[i].frame < s.obs[first].frame)) first = i;
  s.gauge_frame = s.obs[first].frame;
  s.frame_known[s.gauge_frame] = true;
  s.cam_from_world[s.reference] = s.CamFromTarget(setup.target, first);
  s.camera_known[s.reference] = true;
  while (ExtendPoseGraph(setup, s)) {
  }
  std::string lonely;
  for (int c = 0; c < setup.num_cameras; ++c)
    if (!s.camera_known[c]) lonely += (lonely.empty() ? "" : ", ") + setup.input.camera_names[c];
  if (!lonely.empty())
    Fail("camera(s) " + lonely + " share no frame with " + setup.input.camera_names[s.reference] +
         " or the cameras linked to it: show the target to two cameras at the same time");
}

// 4. Pose graph: every camera and target pose, from the reference camera over shared frames.
void InitializePoses(const CalibrationSetup& setup, CalibrationState& s) {
  s.cam_from_world.assign(setup.num_cameras, Rigid3d());
  s.camera_known.assign(setup.num_cameras, false);
  s.world_from_target.assign(std::max(setup.num_frames, 1), Rigid3d());
  s.frame_known.assign(std::max(setup.num_frames, 1), false);
  s.gauge_frame = -1;
  if (setup.marker_map) {
    PoseCamerasOnMarkerMap(setup, s);
  } else {
    ChainPosesFromReference(setup, s);
  }
}

// The bundle adjustment: its parameter blocks (quaternions in Eigen's x, y, z, w order), the
// Ceres problem over them, and one residual block per observed point.
struct BundleAdjustment {
  struct Residual {
    int obs, point;
    ceres::ResidualBlockId id;
  };

  std::vector<std::array<double, 4>> cam_q, frame_q;
  std::vector<std::array<double, 3>> cam_t, frame_t;
  std::vector<std::array<double, kNumIntrinsics>> cam_k;
  std::array<double, 4> map_q = {0, 0, 0, 1};  // a marker map: held at the identity
  std::array<double, 3> map_t = {0, 0, 0};
  ceres::Problem problem;
  std::vector<Residual> residuals;
  std::vector<bool> outlier;  // per residual: dropped from the problem

  // Reprojection error of residual `r`, px (no loss function applied).
  double ResidualNorm(const Residual& r) const {
    double res[2];
    double cost;
    problem.EvaluateResidualBlock(r.id, false, &cost, res, nullptr);
    return std::hypot(res[0], res[1]);
  }
};

// The parameter blocks, from the initial intrinsics and poses.
void InitializeParameters(const CalibrationSetup& setup, const CalibrationState& s,
                          BundleAdjustment& ba) {
  // Allocated in the order they always were: Ceres orders the blocks of an elimination group by
  // address, so the heap layout sets the order of the Schur arithmetic (results to round-off).
  ba.cam_q.resize(setup.num_cameras);
  ba.frame_q.resize(setup.num_frames);
  ba.cam_t.resize(setup.num_cameras);
  ba.frame_t.resize(setup.num_frames);
  ba.cam_k.resize(setup.num_cameras);
  for (int c = 0; c < setup.num_cameras; ++c) {
    Eigen::Map<Eigen::Vector4d>(ba.cam_q[c].data()) = s.cam_from_world[c].rotation.coeffs();
    Eigen::Map<Eigen::Vector3d>(ba.cam_t[c].data()) = s.cam_from_world[c].translation;
    ba.cam_k[c] = s.intrinsics[c].ToParameters();
  }
  for (int f = 0; f < setup.num_frames; ++f) {
    Eigen::Map<Eigen::Vector4d>(ba.frame_q[f].data()) = s.world_from_target[f].rotation.coeffs();
    Eigen::Map<Eigen::Vector3d>(ba.frame_t[f].data()) = s.world_from_target[f].translation;
  }
}

// One Huber-robust reprojection residual per point of every posed view in a known frame.
void AddReprojectionResiduals(const CalibrationSetup& setup, const CalibrationState& s,
                              BundleAdjustment& ba) {
  for (size_t i = 0; i < s.obs.size(); ++i) {
    const Observation& o = s.obs[i];
    if (!s.posed[i] || !s.frame_known[o.frame]) continue;
    double* tq = setup.marker_map ? ba.map_q.data() : ba.frame_q[o.frame].data();
    double* tt = setup.marker_map ? ba.map_t.data() : ba.frame_t[o.frame].data();
    const Rigid3d& target_from_face = setup.target.faces[o.face].target_from_face;
    for (size_t k = 0; k < o.ids.size(); ++k) {
      const Eigen::Vector3d point = target_from_face * setup.pattern.points[o.ids[k]];
      ceres::ResidualBlockId id = ba.problem.AddResidualBlock(
          ReprojectionCostFunctor::Create(o.pixels[k], point),
          new ceres::HuberLoss(setup.options.huber_px), ba.cam_q[o.camera].data(),
          ba.cam_t[o.camera].data(), ba.cam_k[o.camera].data(), tq, tt);
      ba.residuals.push_back({static_cast<int>(i), static_cast<int>(k), id});
    }
  }
  ba.outlier.assign(ba.residuals.size(), false);
}

// Manifolds (unit quaternions; k4..k6 held at zero without the rational model), the intrinsics
// held constant where fixed or not refined, and the gauge: the marker map, or the target in the
// gauge frame.
void ConstrainParameters(const CalibrationSetup& setup, const CalibrationState& s,
                         BundleAdjustment& ba) {
  const CalibrationOptions& options = setup.options;
  for (int c = 0; c < setup.num_cameras; ++c) {
    ba.problem.SetManifold(ba.cam_q[c].data(), new ceres::EigenQuaternionManifold);
    const bool fixed = options.fixed_intrinsics.count(setup.input.camera_names[c]) > 0;
    if (fixed || !options.refine_intrinsics) {
      ba.problem.SetParameterBlockConstant(ba.cam_k[c].data());
    } else if (!options.rational) {
      ba.problem.SetManifold(ba.cam_k[c].data(),
                             new ceres::SubsetManifold(kNumIntrinsics, {9, 10, 11}));
    }
  }
  if (setup.marker_map) {
    ba.problem.SetParameterBlockConstant(ba.map_q.data());
    ba.problem.SetParameterBlockConstant(ba.map_t.data());
  } else {
    for (int f = 0; f < setup.num_frames; ++f) {
      if (!ba.problem.HasParameterBlock(ba.frame_q[f].data())) continue;
      ba.problem.SetManifold(ba.frame_q[f].data(), new ceres::EigenQuaternionManifold);
    }
    // Gauge: the world is the target in the reference camera's first frame.
    ba.problem.SetParameterBlockConstant(ba.frame_q[s.gauge_frame].data());
    ba.problem.SetParameterBlockConstant(ba.frame_t[s.gauge_frame].data());
  }
}

// Outliers: beyond max(outlier_px, 5 sigma), sigma from the median residual (Rayleigh). Removes
// them from the problem and returns how many there were.
int DropOutliers(const CalibrationOptions& options, BundleAdjustment& ba) {
  std::vector<double> norms;
  for (size_t r = 0; r < ba.residuals.size(); ++r)
    if (!ba.outlier[r]) norms.push_back(ba.ResidualNorm(ba.residuals[r]));
  if (norms.empty()) Fail("calibration: no observations left");
  std::vector<double> sorted = norms;
  std::nth_element(sorted.begin(), sorted.begin() + sorted.size() / 2, sorted.end());
  const double sigma = sorted[sorted.size() / 2] / 1.1774;
  const double threshold = std::max(options.outlier_px, 5.0 * sigma);
  int dropped = 0;
  for (size_t r = 0, n = 0; r < ba.residuals.size(); ++r) {
    if (ba.outlier[r]) continue;
    if (norms[n++] > threshold) {
      ba.outlier[r] = true;
      ba.problem.RemoveResidualBlock(ba.residuals[r].id);
      ++dropped;
    }
  }
  return dropped;
}

// 5. Solve; drop the outliers and solve again, at most three solves in all.
void SolveDroppingOutliers(const CalibrationOptions& options, BundleAdjustment& ba) {
  ceres::Solver::Options solver;
  solver.linear_solver_type = ceres::DENSE_SCHUR;
  solver.max_num_iterations = options.max_iterations;
  solver.num_threads = 2;
  solver.function_tolerance = 1e-12;
  solver.parameter_tolerance = 1e-12;
  ceres::Solver::Summary solver_summary;
  for (int round = 0; round < 3; ++round) {
    ceres::Solve(solver, &ba.problem, &solver_summary);
    if (DropOutliers(options, ba) == 0) break;
  }
}

// The solved cameras (intrinsics and cam_from_world) and target poses.
CalibrationResult SolvedRigAndFrames(const CalibrationSetup& setup, const CalibrationState& s,
                                     const BundleAdjustment& ba) {
  CalibrationResult result;
  for (int c = 0; c < setup.num_cameras; ++c) {
    Camera camera;
    camera.name = setup.input.camera_names[c];
    camera.intrinsics = s.intrinsics[c];
    camera.intrinsics.FromParameters(ba.cam_k[c].data());
    camera.intrinsics.rational = setup.options.fixed_intrinsics.count(camera.name)
                                     ? s.intrinsics[c].rational
                                     : setup.options.rational;
    const auto& q = ba.cam_q[c];
    const auto& t = ba.cam_t[c];
    camera.cam_from_world = Rigid3d(Eigen::Quaterniond(q[3], q[0], q[1], q[2]).normalized(),
                                    Eigen::Vector3d(t[0], t[1], t[2]));
    result.rig.cameras.push_back(camera);
  }
  result.world_from_target.assign(setup.num_frames, Rigid3d());
  result.frame_seen.assign(setup.num_frames, false);
  for (int f = 0; f < setup.num_frames && !setup.marker_map; ++f) {
    if (!s.frame_known[f]) continue;
    const auto& q = ba.frame_q[f];
    const auto& t = ba.frame_t[f];
    result.world_from_target[f] = Rigid3d(Eigen::Quaterniond(q[3], q[0], q[1], q[2]).normalized(),
                                          Eigen::Vector3d(t[0], t[1], t[2]));
    result.frame_seen[f] = true;
  }
  return result;
}

// Sums of squared inlier residuals per camera, per image and in all; the 10 x 10 image cells
// each camera's inliers fall in; the number of outliers.
struct ResidualStatistics {
  std::vector<double> sum_camera;
  std::vector<int> count_camera;
  std::map<std::pair<int, int>, std::pair<double, int>> per_image;  // (camera, frame) -> sum, n
  std::vector<std::set<int>> cells;
  double sum_all = 0.0;
  int count_all = 0;
  int outliers = 0;
};

// Residual statistics per camera and image; coverage.
ResidualStatistics SumResiduals(const CalibrationSetup& setup, const CalibrationState& s,
                                const BundleAdjustment& ba) {
  ResidualStatistics stats;
  stats.sum_camera.assign(setup.num_cameras, 0.0);
  stats.count_camera.assign(setup.num_cameras, 0);
  stats.cells.resize(setup.num_cameras);
  for (size_t r = 0; r < ba.residuals.size(); ++r) {
    const Observation& o = s.obs[ba.residuals[r].obs];
    if (ba.outlier[r]) {
      ++stats.outliers;
      continue;
    }
    const double n = ba.ResidualNorm(ba.residuals[r]);
    stats.sum_camera[o.camera] += n * n;
    ++stats.count_camera[o.camera];
    auto& image = stats.per_image[{o.camera, o.frame}];
    image.first += n * n;
    ++image.second;
    stats.sum_all += n * n;
    ++stats.count_all;
    const Eigen::Vector2d& p = o.pixels[ba.residuals[r].point];
    const cv::Size size = setup.input.image_sizes[o.camera];
    const int cx = std::clamp(static_cast<int>(10.0 * p.x() / size.width), 0, 9);
    const int cy = std::clamp(static_cast<int>(10.0 * p.y() / size.height), 0, 9);
    stats.cells[o.camera].insert(cy * 10 + cx);
  }
  return stats;
}

// Camera-centre uncertainty (1 sigma, m) from the solver's covariance, scaled by the residual
// variance; zero where the covariance cannot be computed.
std::vector<double> CameraCentreSigmas(const CalibrationSetup& setup, BundleAdjustment& ba,
                                       const ResidualStatistics& stats, const Rig& rig) {
  const int num_params = ba.problem.NumParameters() - 0;
  const double dof = std::max(1, 2 * stats.count_all - num_params);
  const double variance = stats.sum_all / dof;
  std::vector<double> centre_sigma(setup.num_cameras, 0.0);
  // The gauge is fixed, so the Jacobian has full rank and sparse QR applies (dense SVD took
  // 4 of the 5 s of a 4-camera, 40-view calibration).
  ceres::Covariance::Options cov_options;
  cov_options.algorithm_type = ceres::SPARSE_QR;
  cov_options.num_threads = 2;
  ceres::Covariance covariance(cov_options);
  std::vector<std::pair<const double*, const double*>> blocks;
  for (int c = 0; c < setup.num_cameras; ++c) {
    blocks.emplace_back(ba.cam_q[c].data(), ba.cam_q[c].data());
    blocks.emplace_back(ba.cam_q[c].data(), ba.cam_t[c].data());
    blocks.emplace_back(ba.cam_t[c].data(), ba.cam_t[c].data());
  }
  if (!covariance.Compute(blocks, &ba.problem)) return centre_sigma;
  for (int c = 0; c < setup.num_cameras; ++c) {
    const double* q = ba.cam_q[c].data();
    const double* t_block = ba.cam_t[c].data();
    Eigen::Matrix<double, 3, 3, Eigen::RowMajor> qq, qt, tt;
    covariance.GetCovarianceBlockInTangentSpace(q, q, qq.data());
    covariance.GetCovarianceBlockInTangentSpace(q, t_block, qt.data());
    covariance.GetCovarianceBlockInTangentSpace(t_block, t_block, tt.data());
    // c = -R^T t; EigenQuaternionManifold perturbs on the left (R' = Exp(d) R), so
    // dc/dd = -R^T [t]x and dc/dt = -R^T.
    const Eigen::Matrix3d r = rig.cameras[c].cam_from_world.RotationMatrix();
    const Eigen::Vector3d t = rig.cameras[c].cam_from_world.translation;
    Eigen::Matrix3d tx;
    tx << 0, -t.z(), t.y(), t.z(), 0, -t.x(), -t.y(), t.x(), 0;
    const Eigen::Matrix3d jd = -r.transpose() * tx, jt = -r.transpose();
    const Eigen::Matrix3d cov = jd * qq * jd.transpose() + jd * qt * jt.transpose() +
                                jt * qt.transpose() * jd.transpose() + jt * tt * jt.transpose();
    centre_sigma[c] = std::sqrt(std::max(0.0, variance * cov.trace()));
  }
  return centre_sigma;
}

// Camera `c`'s report: RMS, points, coverage, centre sigma and the RMS of each of its images.
CameraReport ReportCamera(const CalibrationSetup& setup, const ResidualStatistics& stats,
                          const std::vector<double>& centre_sigma, int c) {
  CameraReport report;
  report.name = setup.input.camera_names[c];
  report.points = stats.count_camera[c];
  report.rms_px =
      stats.count_camera[c] ? std::sqrt(stats.sum_camera[c] / stats.count_camera[c]) : 0.0;
  report.coverage = stats.cells[c].size() / 100.0;
  report.position_sigma_m = centre_sigma[c];
  std::set<int> frames;
  for (const auto& [key, value] : stats.per_image) {
    if (key.first != c) continue;
    report.image_rms_px.emplace_back(key.second, std::sqrt(value.first / value.second));
    frames.insert(key.second);
  }
  report.views = static_cast<int>(frames.size());
  return report;
}

// The largest angle (rad) between the target's orientations in two of camera `c`'s posed views.
double ViewSpread(const CalibrationState& s, int c) {
  double spread = 0.0;
  for (int i : s.of_camera[c])
    for (int j : s.of_camera[c])
      if (s.posed[i] && s.posed[j])
        spread = std::max(spread,
                          s.cam_from_face[i].rotation.angularDistance(s.cam_from_face[j].rotation));
  return spread;
}

// Warnings on poor geometry: few views and, where the intrinsics were estimated, views too
// alike (planar targets) or too little of the image covered.
void WarnOnPoorGeometry(const CalibrationSetup& setup, const CalibrationState& s, int c,
                        const CameraReport& report, std::vector<std::string>& warnings) {
  const CalibrationOptions& options = setup.options;
  const bool estimated = !options.fixed_intrinsics.count(report.name);
  if (report.views < options.min_views)
    warnings.push_back("camera " + report.name + ": only " + std::to_string(report.views) +
                       " views (at least " + std::to_string(options.min_views) + " recommended)");
  if (estimated && setup.pattern.planar()) {
    const double spread = ViewSpread(s, c);
    if (spread * 180.0 / M_PI < options.min_view_spread_deg)
      warnings.push_back(
          "camera " + report.name + ": all views are alike (target turned by at most " +
          std::to_string(static_cast<int>(spread * 180.0 / M_PI)) +
          " deg between them): tilt it more, or focal length and distortion stay uncertain");
  }
  if (estimated && report.coverage < options.min_coverage)
    warnings.push_back("camera " + report.name + ": points cover only " + Percent(report.coverage) +
                       " of the image; distortion at its edges is extrapolated");
}

// The baseline of cameras `a` and `b` and the metric check: adjacent points triangulated by the
// two wherever they see the same face in the same frame, against the pattern's spacing.
PairCheck CheckPair(const CalibrationSetup& setup, const CalibrationState& s, const Rig& rig, int a,
                    int b) {
  const std::vector<Observation>& obs = s.obs;
  PairCheck pair;
  pair.a = setup.input.camera_names[a];
  pair.b = setup.input.camera_names[b];
  const Camera& ca = rig.cameras[a];
  const Camera& cb = rig.cameras[b];
  pair.baseline_m = (ca.Center() - cb.Center()).norm();
  double sum_length = 0.0, sum_error2 = 0.0, nominal_sum = 0.0;
  for (int ia : s.of_camera[a]) {
    for (int ib : s.of_camera[b]) {
      if (obs[ia].frame != obs[ib].frame || obs[ia].face != obs[ib].face) continue;
      // The points both views hold, triangulated.
      std::map<int, Eigen::Vector3d> points;
      for (size_t k = 0; k < obs[ia].ids.size(); ++k)
        for (size_t l = 0; l < obs[ib].ids.size(); ++l)
          if (obs[ia].ids[k] == obs[ib].ids[l])
            points[obs[ia].ids[k]] = Triangulate(ca, obs[ia].pixels[k], cb, obs[ib].pixels[l]);
      // Each neighbouring pair of them against its nominal distance.
      for (const auto& [i, j] : setup.pattern.neighbours) {
        const auto pi = points.find(i), pj = points.find(j);
        if (pi == points.end() || pj == points.end()) continue;
        const double length = (pi->second - pj->second).norm();
        const double nominal = (setup.pattern.points[i] - setup.pattern.points[j]).norm();
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
  return pair;
}

// 6. The report: overall and per-camera RMS, coverage, centre sigmas, warnings, and the pair
// checks.
void Summarize(const CalibrationSetup& setup, const CalibrationState& s, BundleAdjustment& ba,
               const Rig& rig, CalibrationSummary& summary) {
  const ResidualStatistics stats = SumResiduals(setup, s, ba);
  summary.outliers = stats.outliers;
  summary.observations = stats.count_all;
  summary.rms_px = stats.count_all ? std::sqrt(stats.sum_all / stats.count_all) : 0.0;
  const std::vector<double> centre_sigma = CameraCentreSigmas(setup, ba, stats, rig);
  for (int c = 0; c < setup.num_cameras; ++c) {
    summary.cameras.push_back(ReportCamera(setup, stats, centre_sigma, c));
    WarnOnPoorGeometry(setup, s, c, summary.cameras.back(), summary.warnings);
  }
  if (summary.outliers > 0)
    summary.warnings.push_back(std::to_string(summary.outliers) + " of " +
                               std::to_string(summary.outliers + summary.observations) +
                               " points dropped as outliers");
  // Baselines and the metric check for each pair of cameras.
  for (int a = 0; a < setup.num_cameras; ++a)
    for (int b = a + 1; b < setup.num_cameras; ++b)
      summary.pairs.push_back(CheckPair(setup, s, rig, a, b));
}

}  // namespace

CalibrationResult CalibrateRig(const CalibrationTarget& target, const CalibrationInput& input,
                               const CalibrationOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  std::string error;
  if (!options.IsValid(&error)) Fail("calibration options: " + error);
  if (input.camera_names.empty()) Fail("calibration: no cameras");
  const CalibrationSetup setup(target, input, options);

  // Initial values: detections, intrinsics, view poses, faces, and the pose graph.
  CalibrationState s;
  GatherDetections(setup, s);
  InitializeIntrinsics(setup, s);
  PoseViews(setup, s);
  ChooseReferenceCamera(setup, s);
  AssignFaces(setup, s);
  InitializePoses(setup, s);

  // The bundle adjustment with outlier rejection.
  BundleAdjustment ba;
  InitializeParameters(setup, s, ba);
  AddReprojectionResiduals(setup, s, ba);
  ConstrainParameters(setup, s, ba);
  SolveDroppingOutliers(options, ba);

  // Results and report.
  CalibrationResult result = SolvedRigAndFrames(setup, s, ba);
  Summarize(setup, s, ba, result.rig, s.summary);
  s.summary.wall_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  result.summary = s.summary;
  return result;
}

std::vector<std::string> ImagesMatching(const std::string& pattern) {
  glob_t g{};
  const int status = glob(pattern.c_str(), GLOB_TILDE | GLOB_BRACE, nullptr, &g);
  std::vector<std::string> files;
  if (status == 0)
    for (size_t i = 0; i < g.gl_pathc; ++i) files.push_back(g.gl_pathv[i]);
  globfree(&g);
  std::sort(files.begin(), files.end());
  return files;
}

CalibrationInput DetectInImages(const std::vector<std::string>& camera_names,
                                const std::vector<std::vector<std::string>>& files,
                                const CalibrationTarget& target, const ProgressReporter& progress,
                                int threads) {
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
    while (!progress.cancelled()) {
      const int task = next++;
      if (task >= total) return;
      const int c = task / num_frames, f = task % num_frames;
      const std::string& file = files[c][f];
      const std::string problem = TruncatedImage(file);
      cv::Mat image;
      if (problem.empty()) image = cv::imread(file, cv::IMREAD_UNCHANGED);
      if (image.empty()) {
        std::lock_guard<std::mutex> lock(mutex);
        if (first_error.empty())
          first_error = file + ": " + (problem.empty() ? "unreadable or not an image" : problem);
        continue;
      }
      sizes[c][f] = image.size();
      found[c][f] = DetectPattern(ToGray8(image), pattern);
      const int d = ++done;
      if (progress.reports()) {
        std::lock_guard<std::mutex> lock(mutex);
        progress.Report("images searched", d, total);
      }
    }
  };
  std::vector<std::thread> pool;
  for (int t = 1; t < std::max(1, threads); ++t) pool.emplace_back(worker);
  worker();
  for (std::thread& t : pool) t.join();
  progress.ThrowIfCancelled();
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
