#include "libreconstruct/twin/synthetic_experiment.h"

#include <yaml-cpp/yaml.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <exception>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <opencv2/imgcodecs.hpp>
#include <random>
#include <sstream>
#include <thread>

#include "calibration/synthetic.h"
#include "calibration/target.h"
#include "common/files.h"
#include "common/hdf5_util.h"
#include "common/yaml_util.h"
#include "libreconstruct/coloring/color_identify.h"
#include "libreconstruct/coloring/net_coloring.h"
#include "libreconstruct/labels/label_set.h"
#include "libreconstruct/recording/experiment.h"

namespace netlab::recon {
namespace {

namespace fs = std::filesystem;

double Seconds(std::chrono::steady_clock::time_point since) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - since).count();
}

// Does the segment from `from` to `to` pass through the box (strictly before `to`)?
bool SegmentHitsBox(const Eigen::Vector3d& from, const Eigen::Vector3d& to, const Box& box) {
  const Eigen::Quaterniond inv = box.orientation.conjugate();
  const Eigen::Vector3d a = inv * (from - box.center), d = inv * (to - from);
  double t0 = 0.0, t1 = 1.0 - 1e-9;
  for (int i = 0; i < 3; ++i) {
    if (std::abs(d[i]) < 1e-15) {
      if (std::abs(a[i]) > box.half_extents[i]) return false;
      continue;
    }
    double ta = (-box.half_extents[i] - a[i]) / d[i], tb = (box.half_extents[i] - a[i]) / d[i];
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta);
    t1 = std::min(t1, tb);
    if (t0 > t1) return false;
  }
  return true;
}

bool SegmentHitsBall(const Eigen::Vector3d& from, const Eigen::Vector3d& to, const Ball& ball) {
  const Eigen::Vector3d d = to - from;
  const double t = std::clamp((ball.center - from).dot(d) / d.squaredNorm(), 0.0, 1.0);
  return (from + t * d - ball.center).norm() < ball.radius;
}

// The double-sided checker foil of the calibration images and its file.
calib::CalibrationTarget Foil() {
  return calib::CalibrationTarget::Foil(calib::BoardPattern::Chessboard(9, 6, 0.06), 0.0005);
}
constexpr char kFoilYaml[] =
    "# The double-sided checker foil of the rendered calibration images (docs/calibration.md).\n"
    "type: double_sided_foil\n"
    "board: {type: chessboard, cols: 9, rows: 6, square: 0.06}\n"
    "thickness: 0.0005\n"
    "flip_axis: y\n";

// ArUco markers on the faces of the target boxes (2 x 2 per face), as the 3D markers on the
// target are: the marker map that puts the rig into the scene's frame. Only faces some camera
// sees within 50 degrees of face-on: markers seen at grazing angles detect with biased corners.
// Empty without a box.
std::vector<std::pair<int, std::array<Eigen::Vector3d, 4>>> TargetMarkers(const Scene& solids,
                                                                          const calib::Rig& rig) {
  std::vector<std::pair<int, std::array<Eigen::Vector3d, 4>>> markers;
  int id = 0;
  for (const Box& box : solids.boxes)
    for (int axis = 0; axis < 3; ++axis)
      for (int sign : {-1, 1}) {
        const int u = (axis + 1) % 3, v = (axis + 2) % 3;
        const Eigen::Matrix3d r = box.orientation.toRotationMatrix();
        const Eigen::Vector3d normal = sign * r.col(axis);
        const Eigen::Vector3d face = box.center + normal * box.half_extents[axis];
        bool seen = false;
        for (const calib::Camera& camera : rig.cameras)
          seen |= (camera.Center() - face).normalized().dot(normal) > std::cos(50.0 * M_PI / 180.0);
        if (!seen) continue;
        const double size = 0.35 * std::min(box.half_extents[u], box.half_extents[v]) * 2.0;
        for (int i : {-1, 1})
          for (int j : {-1, 1}) {
            if (id >= 50) return markers;  // DICT_4X4_50
            // Markers upright where possible: their x axis along a horizontal face direction.
            const Eigen::Vector3d center = box.center + normal * box.half_extents[axis] +
                                           r.col(u) * (0.5 * i * box.half_extents[u]) +
                                           r.col(v) * (0.5 * j * box.half_extents[v]);
            Eigen::Vector3d x_axis = Eigen::Vector3d::UnitZ().cross(normal);
            if (x_axis.norm() < 1e-6) x_axis = r.col(u);
            markers.emplace_back(id++,
                                 calib::MarkerCorners(center, x_axis.normalized(), normal, size));
          }
      }
  return markers;
}

std::string MarkerMapYaml(
    const std::vector<std::pair<int, std::array<Eigen::Vector3d, 4>>>& markers) {
  std::ostringstream os;
  os.precision(10);
  os << "# ArUco markers on the target body's faces (world frame, m), for netlab calibrate with\n"
        "# --fix-intrinsics: corners top-left, top-right, bottom-right, bottom-left.\n"
        "type: marker_map\ndictionary: DICT_4X4_50\nmarkers:\n";
  for (const auto& [id, corners] : markers) {
    os << "  - {id: " << id << ", corners: [";
    for (int k = 0; k < 4; ++k)
      os << (k ? ", " : "") << "[" << corners[k].x() << ", " << corners[k].y() << ", "
         << corners[k].z() << "]";
    os << "]}\n";
  }
  return os.str();
}

// The point nearest to every camera's optical axis (least squares): where the rig looks.
Eigen::Vector3d AimPoint(const calib::Rig& rig) {
  Eigen::Matrix3d a = Eigen::Matrix3d::Zero();
  Eigen::Vector3d b = Eigen::Vector3d::Zero();
  for (const calib::Camera& camera : rig.cameras) {
    const Eigen::Vector3d d = camera.ViewDirection();
    const Eigen::Matrix3d p = Eigen::Matrix3d::Identity() - d * d.transpose();
    a += p;
    b += p * camera.Center();
  }
  // One camera, or parallel axes: 2 m in front of the first camera.
  if (Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(a).eigenvalues()(0) < 1e-3)
    return rig.cameras[0].Center() + 2.0 * rig.cameras[0].ViewDirection();
  return a.ldlt().solve(b);
}

// Writes an image (the format from the extension); std::runtime_error naming the file if not.
void WriteImage(const fs::path& path, const cv::Mat& image) {
  if (!cv::imwrite(path.string(), image))
    throw std::runtime_error(path.string() + ": cannot write");
}

// labels_true.h5: the true pixel of every knot where a camera sees it (visibility 0), as the
// labeling tools would have labeled it perfectly: what `netlab triangulate` takes to turn the
// rendering back into tracks.
void WriteTrueLabels(const fs::path& path, const calib::Rig& rig,
                     const std::vector<std::array<int, 2>>& grid, const std::vector<int>& frames,
                     const std::vector<std::vector<double>>& pixels,
                     const std::vector<std::vector<uint8_t>>& visibility) {
  int rows = 0, cols = 0;
  for (const auto& g : grid) rows = std::max(rows, g[0] + 1), cols = std::max(cols, g[1] + 1);
  std::vector<std::string> names;
  for (const auto& c : rig.cameras) names.push_back(c.name);
  LabelSet labels = LabelSet::Empty(rows, cols, names, frames);
  const size_t knots = grid.size();
  for (size_t c = 0; c < names.size(); ++c)
    for (size_t t = 0; t < frames.size(); ++t)
      for (size_t j = 0; j < knots; ++j) {
        if (visibility[c][t * knots + j] != 0) continue;
        Label& l =
            labels.at(static_cast<int>(c), static_cast<int>(t), grid[j][0] * cols + grid[j][1]);
        l.px = {pixels[c][(t * knots + j) * 2], pixels[c][(t * knots + j) * 2 + 1]};
        l.source = LabelSource::kImported;
        l.confidence = 1.0f;
        l.state = LabelState::kAccepted;
      }
  WriteLabels(path.string(), labels);
}

}  // namespace

SimulatedShot::SimulatedShot(const std::string& path) {
  tracks_ = ReadKnotTracks(path);
  nodes_ = ReadNodePositions(path);
  if (nodes_.empty())
    throw InputError(path + ": no /nodes/position (the scenario needs store_nodes: true)");
  if (tracks_.scenario.empty())
    throw InputError(path + ": no /scenario (not a netlab simulate file)");
  if (tracks_.frames() < 1) throw InputError(path + ": no frames");
  // The scene needs the nets, rods and bodies; not the gravity, frame rotation or drag files, which
  // are named relative to a scenario folder the result file does not know.
  YAML::Node root;
  try {
    root = YAML::Load(tracks_.scenario);
  } catch (const YAML::Exception& e) {
    throw InputError(path + ":/scenario: " + e.what());
  }
  for (const char* key : {"gravity", "rotating_frame", "drag"}) root.remove(key);
  YAML::Emitter emitter;
  emitter << root;
  scenario_ = netsim::ParseScenario(emitter.c_str(), path + ":/scenario", "");
  // Only the geometry: the simulation's stability and contact set-up are not needed to draw it
  // (and refuse some valid results, e.g. a net of one segment per link).
  model_ = std::make_unique<netsim::Model>(netsim::BuildModel(scenario_).first);
  if (static_cast<int>(nodes_.front().size()) != model_->num_nodes())
    throw InputError(path + ": /nodes/position has " + std::to_string(nodes_.front().size()) +
                     " nodes, its scenario builds " + std::to_string(model_->num_nodes()));
  CheckFinite(path);
  for (int k = 0; k < tracks_.knots(); ++k) {
    const int net = tracks_.net.empty() ? 0 : tracks_.net[k];
    const int node = model_->KnotNode(net, tracks_.grid[k][0], tracks_.grid[k][1]);
    if (node < 0) throw InputError(path + ": knot " + std::to_string(k) + " is not in the net");
    knot_nodes_.push_back(node);
  }
  for (size_t n = 0; n < model_->nets.size(); ++n) {
    const netsim::NetInfo& net = model_->nets[n];
    const netsim::NetSpec& spec = scenario_.nets[n];
    const double diameter = model_->materials[net.material].diameter;
    knot_radius_.push_back(spec.knot_mass > 0 ? 1.5 * diameter : 0.0);
    if (spec.corner_mass > 0)
      for (const auto& [r, c] :
           {std::pair{0, 0}, {0, net.cols - 1}, {net.rows - 1, 0}, {net.rows - 1, net.cols - 1}}) {
        corner_nodes_.push_back(model_->KnotNode(static_cast<int>(n), r, c));
        corner_radius_.push_back(spec.corner_radius > 0 ? spec.corner_radius : 0.01);
      }
  }
}

void SimulatedShot::CheckFinite(const std::string& path) const {
  // A NaN would otherwise surface deep in the renderer ("thread 0 point 0 is not finite") after
  // frames were written; checked here, before any output, naming where the simulation broke.
  for (size_t t = 0; t < nodes_.size(); ++t)
    for (size_t n = 0; n < nodes_[t].size(); ++n) {
      if (nodes_[t][n].allFinite()) continue;
      std::ostringstream os;
      os << path << ": /nodes/position is not finite at frame " << t
         << " (t = " << (t < tracks_.time.size() ? tracks_.time[t] : std::nan("")) << " s), node "
         << n << " (" << model_->DescribeNode(static_cast<int>(n)) << "): (" << nodes_[t][n].x()
         << ", " << nodes_[t][n].y() << ", " << nodes_[t][n].z() << ")";
      throw InputError(os.str());
    }
}

std::vector<Eigen::Vector3d> SimulatedShot::NodesAt(double t) const {
  const std::vector<double>& time = tracks_.time;
  if (t <= time.front()) return nodes_.front();
  if (t >= time.back()) return nodes_.back();
  const size_t i = std::upper_bound(time.begin(), time.end(), t) - time.begin() - 1;
  const double s = (t - time[i]) / (time[i + 1] - time[i]);
  std::vector<Eigen::Vector3d> x(nodes_[i].size());
  for (size_t n = 0; n < x.size(); ++n) x[n] = (1.0 - s) * nodes_[i][n] + s * nodes_[i + 1][n];
  return x;
}

std::vector<Eigen::Vector3d> SimulatedShot::KnotsAt(
    const std::vector<Eigen::Vector3d>& nodes) const {
  std::vector<Eigen::Vector3d> knots;
  knots.reserve(knot_nodes_.size());
  for (int node : knot_nodes_) knots.push_back(nodes[node]);
  return knots;
}

Scene SimulatedShot::SolidsAt(double t, const std::vector<Eigen::Vector3d>& nodes) const {
  Scene scene;
  const Colour body_colour(0.55f, 0.55f, 0.55f), corner_colour(0.7f, 0.7f, 0.7f);
  for (const netsim::RigidBody& body : scenario_.bodies) {
    const Eigen::Vector3d center = body.center + t * body.velocity;
    if (body.shape == netsim::RigidBody::Shape::kBox)
      scene.boxes.push_back({center, body.orientation, body.half_extents, body_colour});
    else if (body.shape == netsim::RigidBody::Shape::kSphere)
      scene.balls.push_back({center, body.radius, body_colour});
    // Planes (a wall or a floor) are not drawn: they would fill the view.
  }
  for (size_t i = 0; i < corner_nodes_.size(); ++i)
    scene.balls.push_back({nodes[corner_nodes_[i]], corner_radius_[i], corner_colour});
  return scene;
}

Scene SimulatedShot::SceneAt(double t, const std::vector<YarnColoring>& coloring,
                             Colour background) const {
  const std::vector<Eigen::Vector3d> x = NodesAt(t);
  Scene scene = SolidsAt(t, x);
  scene.background = background;
  for (size_t n = 0; n < model_->nets.size(); ++n) {
    const netsim::NetInfo& net = model_->nets[n];
    const YarnColoring fallback =
        n < coloring.size() ? YarnColoring{} : DefaultColoring(net.rows, net.cols);
    const YarnColoring& colours = n < coloring.size() ? coloring[n] : fallback;
    const double radius = 0.5 * model_->materials[net.material].diameter;
    const int interior = net.segments_per_link - 1;
    for (int link = 0; link < net.num_links(); ++link) {
      const auto k = LinkKnots(net.rows, net.cols, link);
      ThreadPolyline yarn;
      yarn.radius = radius;
      yarn.colour = colours.palette[colours.link_colour[link] % colours.palette.size()];
      yarn.points.push_back(x[model_->KnotNode(static_cast<int>(n), k[0], k[1])]);
      for (int j = 0; j < interior; ++j)
        yarn.points.push_back(x[net.first_node + net.rows * net.cols + link * interior + j]);
      yarn.points.push_back(x[model_->KnotNode(static_cast<int>(n), k[2], k[3])]);
      scene.threads.push_back(std::move(yarn));
    }
    if (knot_radius_[n] > 0)
      for (int r = 0; r < net.rows; ++r)
        for (int c = 0; c < net.cols; ++c)
          scene.balls.push_back({x[model_->KnotNode(static_cast<int>(n), r, c)], knot_radius_[n],
                                 Colour(0.5f, 0.5f, 0.5f)});
  }
  for (const netsim::RodInfo& rod : model_->rods) {
    ThreadPolyline yarn;
    yarn.radius = 0.5 * model_->materials[rod.material].diameter;
    yarn.colour = Colour(0.7f, 0.7f, 0.7f);
    for (int i = 0; i < rod.num_nodes; ++i) yarn.points.push_back(x[rod.first_node + i]);
    scene.threads.push_back(std::move(yarn));
  }
  return scene;
}

uint8_t KnotVisibility(const calib::Camera& camera, const Eigen::Vector3d& knot,
                       const Scene& solids, double ignore_radius) {
  const Eigen::Vector3d in_cam = camera.cam_from_world * knot;
  if (!(in_cam.z() > 0)) return 2;
  const Eigen::Vector2d px = calib::Project(camera.intrinsics, in_cam);
  if (!(px.x() >= -0.5 && px.y() >= -0.5 && px.x() <= camera.intrinsics.width - 0.5 &&
        px.y() <= camera.intrinsics.height - 0.5))
    return 2;
  const Eigen::Vector3d center = camera.Center();
  for (const Box& box : solids.boxes)
    if (SegmentHitsBox(center, knot, box)) return 1;
  for (const Ball& ball : solids.balls) {
    // A ball holding the knot is its own corner mass: the knot is where the mass is seen.
    if ((ball.center - knot).norm() < ball.radius + ignore_radius) continue;
    if (SegmentHitsBall(center, knot, ball)) return 1;
  }
  return 0;
}

calib::Rig ScaleRig(const calib::Rig& rig, double scale) {
  calib::Rig scaled = rig;
  for (calib::Camera& c : scaled.cameras) {
    calib::CameraIntrinsics& k = c.intrinsics;
    k.fx *= scale;
    k.fy *= scale;
    // Pixel centres at integers: the image's outer edge (-1/2) stays where it is.
    k.cx = (k.cx + 0.5) * scale - 0.5;
    k.cy = (k.cy + 0.5) * scale - 0.5;
    k.width = static_cast<int>(std::lround(k.width * scale));
    k.height = static_cast<int>(std::lround(k.height * scale));
  }
  return scaled;
}

namespace {

// Throws InputError when a net's colouring has not one colour per link of the net.
void CheckColouring(const std::vector<YarnColoring>& coloring, const std::string& file,
                    const netsim::Model& model) {
  for (size_t n = 0; n < coloring.size() && n < model.nets.size(); ++n) {
    const netsim::NetInfo& net = model.nets[n];
    if (static_cast<int>(coloring[n].link_colour.size()) != net.num_links())
      throw InputError((file.empty() ? std::string() : file + ": ") + "the colouring has " +
                       std::to_string(coloring[n].link_colour.size()) + " links, net '" + net.name +
                       "' (" + std::to_string(net.rows) + "x" + std::to_string(net.cols) +
                       " knots) has " + std::to_string(net.num_links()));
  }
}

// The frames to render, first..last: frame k is at time start + k / fps of the simulation.
struct FrameRange {
  double start_time = 0.0;  // s
  double fps = 0.0;
  int first = 0, last = 0;

  int count() const { return last - first + 1; }
  double Time(int k) const { return start_time + k / fps; }
};

// Camera c's clock offset, frames (0 without one).
double OffsetOf(const RenderJob& job, int c) {
  return static_cast<size_t>(c) < job.camera_time_offset_frames.size()
             ? job.camera_time_offset_frames[c]
             : 0.0;
}

// Camera c of the rig at time t (where its motion, if any, has taken it).
calib::Camera CameraAt(const RenderJob& job, int c, double t) {
  return static_cast<size_t>(c) < job.camera_motion.size()
             ? job.camera_motion[c].At(job.rig.cameras[c], t)
             : job.rig.cameras[c];
}

// Camera c's response (the identity without one).
CameraResponse ResponseOf(const RenderJob& job, int c) {
  return static_cast<size_t>(c) < job.responses.size() ? job.responses[c] : CameraResponse();
}

}  // namespace

void CheckOutsideOutput(const std::string& input, const std::string& option,
                        const std::string& out_dir) {
  if (IsInsideFolder(input, out_dir))
    throw InputError(option + " " + input + " is inside the output folder " + out_dir +
                     ", which render replaces as a whole; render into another folder");
}

namespace {

// The job's frames; InputError when they are not within the simulation.
FrameRange FramesOf(const RenderJob& job, const SimulatedShot& shot) {
  if (!(job.fps > 0)) throw InputError("fps must be > 0");
  const int available =
      static_cast<int>(std::floor((shot.end_time() - shot.start_time()) * job.fps + 1e-6));
  const int first = job.first_frame;
  const int last = job.last_frame < 0 ? available : job.last_frame;
  if (first < 0 || last < first || last > available)
    throw InputError(job.simulation + ": frames " + std::to_string(first) + ":" +
                     std::to_string(last) + " are outside the simulation's frames 0:" +
                     std::to_string(available) + " at " + std::to_string(job.fps) + " fps (" +
                     std::to_string(shot.end_time() - shot.start_time()) + " s of /time)");
  const FrameRange range{shot.start_time(), job.fps, first, last};
  // A camera's clock offset must keep its exposures within the simulation too.
  if (!job.camera_time_offset_frames.empty() &&
      job.camera_time_offset_frames.size() != job.rig.cameras.size())
    throw std::invalid_argument("RenderJob: one clock offset per rig camera");
  for (size_t c = 0; c < job.camera_time_offset_frames.size(); ++c) {
    const double d = job.camera_time_offset_frames[c];
    if (!(std::abs(d) < 1.0))
      throw InputError("--camera-time-offset " + job.rig.cameras[c].name + "=" + std::to_string(d) +
                       ": a clock offset is a fraction of a frame (-1 < d < 1)");
    if (range.Time(first) + d / job.fps < shot.start_time() - 1e-9 ||
        range.Time(last) + d / job.fps > shot.end_time() + 1e-9)
      throw InputError("--camera-time-offset " + job.rig.cameras[c].name + "=" + std::to_string(d) +
                       ": frames " + std::to_string(first) + ":" + std::to_string(last) +
                       " of that camera would be exposed outside the "
                       "simulation's time; render fewer frames");
  }
  return range;
}

// The job with its effects checked (InputError naming the option) and a camera's step without
// a time (NaN) put half a frame before the middle frame of the range.
RenderJob WithEffectsChecked(const RenderJob& given, const FrameRange& range) {
  RenderJob job = given;
  std::string error;
  if (!job.flicker.IsValid(&error)) throw InputError("--flicker: " + error);
  if (!job.depth_of_field.IsValid(&error)) throw InputError("--f-number: " + error);
  const size_t cameras = job.rig.cameras.size();
  if (!job.responses.empty() && job.responses.size() != cameras)
    throw std::invalid_argument("RenderJob: one response per rig camera");
  for (size_t c = 0; c < job.responses.size(); ++c)
    if (!job.responses[c].IsValid(&error))
      throw InputError("camera " + job.rig.cameras[c].name + "'s response: " + error);
  if (!job.camera_motion.empty() && job.camera_motion.size() != cameras)
    throw std::invalid_argument("RenderJob: one camera motion per rig camera");
  if (job.paper_lamps) job.lamps = PaperLamps(job.rig, AimPoint(job.rig));
  for (const Lamp& lamp : job.lamps.lamps)
    if (!lamp.position.allFinite() || !(lamp.power >= 0.0))
      throw InputError("--lamps: a lamp needs a finite position and a power >= 0");
  for (CameraMotion& motion : job.camera_motion)
    if (motion.enabled() && motion.hz == 0.0 && !std::isfinite(motion.step_time))
      motion.step_time = range.Time(range.first + range.count() / 2) - 0.5 / range.fps;
  return job;
}

// The experiment file's content, each camera's folder made and its timestamps.csv written.
Experiment PrepareExperiment(const RenderJob& job, const FrameRange& range, const fs::path& out) {
  Experiment experiment;
  experiment.name = fs::path(job.simulation).stem().string() + "_rendered";
  experiment.fps = job.fps;
  experiment.path = (out / "experiment.yaml").string();
  experiment.base_dir = out.string();
  for (const calib::Camera& camera : job.rig.cameras) {
    fs::create_directories(out / camera.name);
    std::ostringstream times;
    times << "frame_index,time_s\n";
    times.precision(12);
    for (int k = range.first; k <= range.last; ++k) times << k << "," << range.Time(k) << "\n";
    WriteTextFile((out / camera.name / "timestamps.csv").string(), times.str());
    CameraSpec spec;
    spec.name = camera.name;
    spec.frames = camera.name + "/frame_%06d.pgm";
    spec.bayer = job.sensor.bayer;
    spec.timestamps = (out / camera.name / "timestamps.csv").string();
    spec.bit_depth = job.sensor.bit_depth;
    spec.black_level = job.sensor.black_level;
    experiment.cameras.push_back(spec);
  }
  return experiment;
}

// Runs `work` on `threads` threads (at least one: this one), waits for them all and rethrows the
// first exception any of them threw (one escaping a std::thread would terminate the process).
void RunOnThreads(int threads, const std::function<void()>& work) {
  std::mutex mutex;
  std::exception_ptr failure;
  const auto guarded = [&] {
    try {
      work();
    } catch (...) {
      std::lock_guard<std::mutex> lock(mutex);
      if (!failure) failure = std::current_exception();
    }
  };
  std::vector<std::thread> pool;
  for (int t = 1; t < std::max(1, threads); ++t) pool.emplace_back(guarded);
  guarded();
  for (std::thread& t : pool) t.join();
  if (failure) std::rethrow_exception(failure);
}

// Renders frame k of camera c: the scene averaged over the exposure (blur samples), exposed by
// the sensor, written as out/<camera>/frame_%06d.pgm.
// `backgrounds`: per camera, the textile panel it sees (empty without one).
void RenderFrame(const RenderJob& job, const SimulatedShot& shot, const FrameRange& range,
                 const fs::path& out, int k, int c, const std::vector<cv::Mat>& backgrounds) {
  SceneRenderOptions render_options;
  if (static_cast<size_t>(c) < backgrounds.size() && !backgrounds[c].empty())
    render_options.background_image = &backgrounds[c];
  if (job.lamps.enabled()) {
    render_options.lamps = job.lamps.lamps;
    render_options.ambient = job.lamps.ambient;
    render_options.glossy = job.lamps.glossy * job.illumination;
    render_options.shininess = job.lamps.shininess;
  }
  const int samples = std::max(1, job.blur_samples);
  const calib::Camera& camera = job.rig.cameras[c];
  const double frame_time = range.Time(k) + OffsetOf(job, c) / range.fps;
  const bool blur = job.depth_of_field.enabled();
  cv::Mat accumulator, depth;
  for (int s = 0; s < samples; ++s) {
    const double t =
        frame_time + ((s + 0.5) / samples - 0.5) * (samples > 1 ? job.exposure_s : 0.0);
    Scene scene = shot.SceneAt(t, job.coloring, job.background);
    for (ThreadPolyline& yarn : scene.threads) yarn.colour *= job.illumination;
    for (Ball& ball : scene.balls) ball.colour *= job.illumination;
    for (Box& box : scene.boxes) box.colour *= job.illumination;
    RenderScene(CameraAt(job, c, t), scene, render_options, 1.0f / samples, &accumulator,
                blur ? &depth : nullptr);
  }
  // The light of the exposure (the whole scene is lit by the flickering lamps), then the lens.
  if (job.flicker.enabled())
    accumulator *= job.flicker.MeanOverExposure(frame_time, job.exposure_s);
  if (blur)
    accumulator = ApplyDepthOfField(accumulator, depth, camera.intrinsics.fx, job.depth_of_field);
  SensorOptions sensor = job.sensor;
  sensor.response = ResponseOf(job, c);
  sensor.seed = job.sensor.seed * 1000003ull + static_cast<uint64_t>(k) * 16 + c;
  const cv::Mat raw = Expose(accumulator, camera.intrinsics, sensor);
  char name[32];
  std::snprintf(name, sizeof(name), "frame_%06d.pgm", k);
  WriteImage(out / camera.name / name, raw);
}

// Renders every (frame, camera) on job.threads threads, reporting progress after each; the first
// failure stops them and is thrown as std::runtime_error, a cancel as Cancelled.
void RenderFrames(const RenderJob& job, const SimulatedShot& shot, const FrameRange& range,
                  const fs::path& out, const ProgressReporter& progress) {
  const int cameras = static_cast<int>(job.rig.cameras.size());
  std::vector<cv::Mat> backgrounds(cameras);
  if (job.textile_background)
    for (int c = 0; c < cameras; ++c)
      backgrounds[c] =
          TextileBackground(job.rig.cameras[c].intrinsics, kTextileAlbedo * job.illumination,
                            job.background_clutter, job.sensor.seed * 31 + c);
  const int total = range.count() * cameras;
  std::atomic<int> next{0}, done{0};
  std::mutex mutex;
  std::string failure;
  RunOnThreads(job.threads, [&] {
    for (int task; !progress.cancelled() && (task = next++) < total;) {
      try {
        RenderFrame(job, shot, range, out, range.first + task / cameras, task % cameras,
                    backgrounds);
      } catch (const std::exception& e) {
        std::lock_guard<std::mutex> lock(mutex);
        if (failure.empty()) failure = e.what();
        next = total;
      }
      const int d = ++done;
      if (progress.reports()) {
        std::lock_guard<std::mutex> lock(mutex);
        progress.Report("frames rendered", d, total);
      }
    }
  });
  progress.ThrowIfCancelled();
  if (!failure.empty()) throw std::runtime_error(failure);
}

// The truth of the rendered frames: the knots at the frame times, their pixels and visibility
// per camera, and how many each camera sees.
struct FrameTruth {
  KnotTracks tracks;
  std::vector<int> frame_index;                  // [T] the camera frame of each row
  std::vector<std::vector<double>> pixels;       // [camera][T * K * 2] px
  std::vector<std::vector<uint8_t>> visibility;  // [camera][T * K] (KnotVisibility's codes)
  std::vector<double> knots_visible_mean;        // per camera: visible knots per frame, mean
  std::vector<int> knots_visible_min;            // per camera
  std::vector<std::vector<double>> rotation;     // [camera][T * 9] cam_from_world, row-major
  std::vector<std::vector<double>> translation;  // [camera][T * 3] m
};

// The truth of the frames of `range` as `rig` sees them (each camera at its own clock).
FrameTruth TruthOf(const SimulatedShot& shot, const RenderJob& job, const FrameRange& range) {
  const calib::Rig& rig = job.rig;
  const int frames = range.count(), cameras = static_cast<int>(rig.cameras.size());
  FrameTruth truth;
  truth.tracks.grid = shot.tracks().grid;
  truth.tracks.net = shot.tracks().net;
  truth.tracks.net_names = shot.tracks().net_names;
  truth.tracks.source = "netlab render";
  truth.tracks.scenario = shot.tracks().scenario;
  const int knots = truth.tracks.knots();
  truth.pixels.assign(cameras, std::vector<double>(size_t(frames) * knots * 2));
  truth.visibility.assign(cameras, std::vector<uint8_t>(size_t(frames) * knots));
  truth.knots_visible_mean.assign(cameras, 0.0);
  truth.knots_visible_min.assign(cameras, knots);
  truth.rotation.assign(cameras, {});
  truth.translation.assign(cameras, {});
  for (int k = range.first; k <= range.last; ++k) {
    // The knots at the frame time, and the solids that can hide them.
    const double t = range.Time(k);
    const std::vector<Eigen::Vector3d> nodes = shot.NodesAt(t);
    const std::vector<Eigen::Vector3d> x = shot.KnotsAt(nodes);
    const Scene solids = shot.SolidsAt(t, nodes);
    truth.tracks.time.push_back(t);
    truth.frame_index.push_back(k);
    for (int j = 0; j < knots; ++j) {
      truth.tracks.position.push_back(x[j]);
      truth.tracks.valid.push_back(1);
    }
    // Their pixels and visibility in each camera, at the camera's own time.
    const size_t row = k - range.first;
    for (int c = 0; c < cameras; ++c) {
      int visible = 0;
      const double offset = OffsetOf(job, c);
      std::vector<Eigen::Vector3d> x_c;
      Scene solids_c;
      if (offset != 0.0) {
        const std::vector<Eigen::Vector3d> nodes_c = shot.NodesAt(t + offset / range.fps);
        x_c = shot.KnotsAt(nodes_c);
        solids_c = shot.SolidsAt(t + offset / range.fps, nodes_c);
      }
      const std::vector<Eigen::Vector3d>& seen = offset != 0.0 ? x_c : x;
      const Scene& hiding = offset != 0.0 ? solids_c : solids;
      // The camera where it was at its own time.
      const calib::Camera camera = CameraAt(job, c, t + offset / range.fps);
      const Eigen::Matrix3d r = camera.cam_from_world.RotationMatrix();
      for (int a = 0; a < 3; ++a) {
        for (int b = 0; b < 3; ++b) truth.rotation[c].push_back(r(a, b));
        truth.translation[c].push_back(camera.cam_from_world.translation[a]);
      }
      for (int j = 0; j < knots; ++j) {
        const Eigen::Vector2d px = camera.ProjectWorld(seen[j]);
        truth.pixels[c][(row * knots + j) * 2] = px.x();
        truth.pixels[c][(row * knots + j) * 2 + 1] = px.y();
        const uint8_t v = KnotVisibility(camera, seen[j], hiding);
        truth.visibility[c][row * knots + j] = v;
        visible += v == 0;
      }
      truth.knots_visible_mean[c] += visible / static_cast<double>(frames);
      truth.knots_visible_min[c] = std::min(truth.knots_visible_min[c], visible);
    }
  }
  return truth;
}

// The effects a job films with, as YAML (truth.h5 /effects).
std::string EffectsYaml(const RenderJob& job) {
  std::ostringstream os;
  os.precision(10);
  os << "flicker: {hz: " << job.flicker.hz << ", depth: " << job.flicker.depth
     << ", duty: " << job.flicker.duty << "}\n";
  os << "depth_of_field: {f_number: " << job.depth_of_field.f_number
     << ", focus_distance_m: " << job.depth_of_field.focus_distance_m
     << ", pixel_pitch_m: " << job.depth_of_field.pixel_pitch_m << "}\n";
  os << "lamps: {ambient: " << job.lamps.ambient << ", glossy: " << job.lamps.glossy
     << ", shininess: " << job.lamps.shininess << ", lamps: [";
  for (size_t i = 0; i < job.lamps.lamps.size(); ++i) {
    const Lamp& lamp = job.lamps.lamps[i];
    os << (i ? ", " : "") << "{position: [" << lamp.position.x() << ", " << lamp.position.y()
       << ", " << lamp.position.z() << "], power: " << lamp.power << "}";
  }
  os << "]}\n";
  os << "background: " << (job.textile_background ? "textile" : "plain")
     << "\nbackground_clutter: " << (job.background_clutter ? "true" : "false") << "\n";
  os << "camera_motion:\n";
  for (size_t c = 0; c < job.rig.cameras.size(); ++c) {
    const CameraMotion m = c < job.camera_motion.size() ? job.camera_motion[c] : CameraMotion();
    os << "  " << job.rig.cameras[c].name << ": {amplitude_m: " << m.amplitude_m << ", hz: " << m.hz
       << ", direction: [" << m.direction.x() << ", " << m.direction.y() << ", " << m.direction.z()
       << "], phase: " << m.phase << ", step_time: " << m.step_time << "}\n";
  }
  return os.str();
}

// truth.h5 (see synthetic_experiment.h), written whole under another name first; the rig's text
// is read back from out/rig_true.yaml.
void WriteTruth(const fs::path& out, const RenderJob& job, const FrameTruth& truth) {
  const calib::Rig& rig = job.rig;
  const int frames = static_cast<int>(truth.frame_index.size());
  const int knots = truth.tracks.knots();
  const fs::path truth_path = out / "truth.h5";
  const std::string writing = truth_path.string() + ".writing";
  WriteKnotTracks(writing, truth.tracks);
  {
    std::lock_guard<std::mutex> lock(h5::Mutex());
    h5::Id file = h5::OpenFileReadWrite(writing);
    h5::WriteDataset(file.get(), "frame_index", H5T_NATIVE_INT32, {static_cast<hsize_t>(frames)},
                     truth.frame_index.data());
    h5::Id group = h5::CreateGroup(file.get(), "cameras");
    for (size_t c = 0; c < rig.cameras.size(); ++c) {
      h5::Id camera = h5::CreateGroup(group.get(), rig.cameras[c].name);
      h5::WriteDataset(camera.get(), "knots_px", H5T_NATIVE_DOUBLE,
                       {static_cast<hsize_t>(frames), static_cast<hsize_t>(knots), 2},
                       truth.pixels[c].data());
      h5::SetUnits(camera.get(), "knots_px", "px");
      h5::WriteDataset(camera.get(), "visibility", H5T_NATIVE_UINT8,
                       {static_cast<hsize_t>(frames), static_cast<hsize_t>(knots)},
                       truth.visibility[c].data());
      h5::WriteDataset(camera.get(), "cam_from_world_rotation", H5T_NATIVE_DOUBLE,
                       {static_cast<hsize_t>(frames), 3, 3}, truth.rotation[c].data());
      h5::WriteDataset(camera.get(), "cam_from_world_translation", H5T_NATIVE_DOUBLE,
                       {static_cast<hsize_t>(frames), 3}, truth.translation[c].data());
      h5::SetUnits(camera.get(), "cam_from_world_translation", "m");
      const CameraResponse response = ResponseOf(job, static_cast<int>(c));
      h5::Id group_r = h5::CreateGroup(camera.get(), "response");
      h5::WriteDataset(group_r.get(), "white_balance", H5T_NATIVE_DOUBLE, {3},
                       response.white_balance.data());
      h5::WriteStringAttribute(h5::Id(H5Dopen2(group_r.get(), "white_balance", H5P_DEFAULT)).get(),
                               "order", "B,G,R");
      const std::pair<const char*, double> values[] = {
          {"gain", response.gain},
          {"gamma", response.gamma},
          {"prnu", response.prnu},
          {"dsnu", response.dsnu},
          {"hot_pixels", response.hot_pixels},
          {"pattern_seed", static_cast<double>(response.pattern_seed)}};
      for (const auto& [name, value] : values)
        h5::WriteDataset(group_r.get(), name, H5T_NATIVE_DOUBLE, {1}, &value);
    }
    h5::WriteStringDataset(file.get(), "effects", EffectsYaml(job));
    std::ifstream rig_file(out / "rig_true.yaml");
    std::stringstream rig_text;
    rig_text << rig_file.rdbuf();
    h5::WriteStringDataset(file.get(), "rig", rig_text.str());
    std::vector<double> offsets;
    std::string names;
    for (size_t c = 0; c < rig.cameras.size(); ++c) {
      offsets.push_back(OffsetOf(job, static_cast<int>(c)));
      names += (c ? "\n" : "") + rig.cameras[c].name;
    }
    h5::WriteDataset(file.get(), "camera_time_offset_frames", H5T_NATIVE_DOUBLE, {offsets.size()},
                     offsets.data());
    h5::SetUnits(file.get(), "camera_time_offset_frames", "frames");
    h5::Id dataset(H5Dopen2(file.get(), "camera_time_offset_frames", H5P_DEFAULT));
    h5::WriteStringAttribute(dataset.get(), "cameras", names);
  }
  RenameInto(writing, truth_path.string());
}

// The render options of the calibration images.
calib::RenderOptions CalibrationRenderOptions(const RenderJob& job) {
  calib::RenderOptions options;
  options.noise_sigma = std::max(1.0, job.sensor.noise_sigma);
  return options;
}

// The foil's poses of the calibration views. Half the views where every camera sees the foil
// (they tie the cameras into one frame), the others nearer to one camera each, so the foil also
// covers the edges of the wide views where distortion is largest.
std::vector<calib::Rigid3d> FoilPoses(const RenderJob& job, const calib::CalibrationTarget& foil) {
  const calib::Rig& rig = job.rig;
  const int cameras = static_cast<int>(rig.cameras.size());
  std::mt19937 rng(static_cast<unsigned>(job.sensor.seed));
  std::vector<int> all(cameras);
  for (int c = 0; c < cameras; ++c) all[c] = c;
  const Eigen::Vector3d aim = AimPoint(rig);
  const Eigen::Quaterniond facing = calib::FacingPlusX(foil.faces[0].pattern);
  const int shared = (job.calibration_views + 1) / 2;
  std::vector<calib::Rigid3d> poses =
      calib::RandomTargetPoses(rig, foil, all, shared, aim + Eigen::Vector3d(0.25, 0.0, 0.1),
                               Eigen::Vector3d(0.35, 0.35, 0.3), facing, 0.6, rng);
  for (int i = 0; i < job.calibration_views - shared; ++i) {
    const int c = i % cameras;
    const Eigen::Vector3d near = aim + 0.45 * (rig.cameras[c].Center() - aim);
    try {
      const auto pose = calib::RandomTargetPoses(rig, foil, {c}, 1, near,
                                                 Eigen::Vector3d(0.2, 0.2, 0.15), facing, 0.5, rng);
      poses.push_back(pose.front());
    } catch (const std::runtime_error&) {
      // This camera cannot see the whole foil that close: the shared views cover it.
    }
  }
  return poses;
}

// Renders the foil at `poses` in every camera into out/calibration/<camera>/view_%03d.png, the
// views of a camera on job.threads threads; returns the number of images.
int RenderFoilViews(const RenderJob& job, const calib::CalibrationTarget& foil,
                    const std::vector<calib::Rigid3d>& poses, const fs::path& out) {
  const auto prints = calib::MakeTargetPrints(foil);
  const calib::RenderOptions options = CalibrationRenderOptions(job);
  int images = 0;
  for (size_t c = 0; c < job.rig.cameras.size(); ++c) {
    const calib::Camera& camera = job.rig.cameras[c];
    fs::create_directories(out / "calibration" / camera.name);
    const calib::CameraRays rays(camera.intrinsics);
    std::atomic<int> view{0};
    RunOnThreads(job.threads, [&] {
      calib::RenderOptions o = options;
      for (int v; (v = view++) < static_cast<int>(poses.size());) {
        o.seed = job.sensor.seed * 7919 + static_cast<uint64_t>(c) * 1000 + v;
        char name[32];
        std::snprintf(name, sizeof(name), "view_%03d.png", v);
        WriteImage(out / "calibration" / camera.name / name,
                   calib::RenderTarget(camera, rays, prints, poses[v], o));
      }
    });
    images += static_cast<int>(poses.size());
  }
  return images;
}

// The marker map on the target (calibration/markers.yaml) and one image of it per camera
// (calibration/markers/<camera>/view_000.png: the markers do not move); none without a target
// box. Returns the number of images.
int RenderMarkerViews(const RenderJob& job, const SimulatedShot& shot, const fs::path& out) {
  const auto markers =
      TargetMarkers(shot.SolidsAt(shot.start_time(), shot.NodesAt(shot.start_time())), job.rig);
  if (markers.empty()) return 0;
  WriteTextFile((out / "calibration" / "markers.yaml").string(), MarkerMapYaml(markers));
  const calib::CalibrationTarget map = calib::CalibrationTarget::MarkerMap("DICT_4X4_50", markers);
  const auto map_prints = calib::MakeTargetPrints(map);
  int images = 0;
  for (const calib::Camera& camera : job.rig.cameras) {
    fs::create_directories(out / "calibration" / "markers" / camera.name);
    calib::RenderOptions o = CalibrationRenderOptions(job);
    o.seed = job.sensor.seed * 7919 + 999;
    WriteImage(out / "calibration" / "markers" / camera.name / "view_000.png",
               calib::RenderTarget(camera, calib::CameraRays(camera.intrinsics), map_prints,
                                   calib::Rigid3d(), o));
    ++images;
  }
  return images;
}

// Calibration images: the double-sided foil at poses every camera sees, and the marker map.
// Returns the number of images.
int RenderCalibrationImages(const RenderJob& job, const SimulatedShot& shot, const fs::path& out) {
  const calib::CalibrationTarget foil = Foil();
  fs::create_directories(out / "calibration");
  WriteTextFile((out / "calibration" / "foil.yaml").string(), kFoilYaml);
  const std::vector<calib::Rigid3d> poses = FoilPoses(job, foil);
  const int foil_images = RenderFoilViews(job, foil, poses, out);
  return foil_images + RenderMarkerViews(job, shot, out);
}

}  // namespace

RenderSummary RenderExperiment(const RenderJob& given, const ProgressReporter& progress) {
  const auto start = std::chrono::steady_clock::now();
  // Check the job against the simulation.
  const SimulatedShot shot(given.simulation);
  CheckColouring(given.coloring, given.coloring_file, shot.model());
  const calib::Rig& rig = given.rig;
  if (rig.cameras.empty()) throw InputError("the rig has no cameras");
  const FrameRange range = FramesOf(given, shot);
  const RenderJob job = WithEffectsChecked(given, range);
  CheckOutsideOutput(job.simulation, "--sim", job.out_dir);

  // The whole folder is written as out_dir.partial and replaces out_dir only when complete: a
  // failing run leaves an existing shot as it was, and a shorter one leaves no stale frames.
  // experiment.yaml names its files relative to its folder, so the folder moves whole.
  FolderReplacement folder(job.out_dir);
  const fs::path out(folder.partial());
  calib::WriteRig((out / "rig_true.yaml").string(), rig);
  const Experiment experiment = PrepareExperiment(job, range, out);

  // Frames: every (frame, camera) on job.threads threads.
  const auto render_start = std::chrono::steady_clock::now();
  RenderFrames(job, shot, range, out, progress);
  const double render_s = Seconds(render_start);
  WriteExperiment(experiment.path, experiment);

  // Truth: the knots at the frame times, their pixels and visibility per camera.
  FrameTruth truth = TruthOf(shot, job, range);
  WriteTruth(out, job, truth);
  WriteTrueLabels(out / "labels_true.h5", rig, truth.tracks.grid, truth.frame_index, truth.pixels,
                  truth.visibility);

  RenderSummary summary;
  // Calibration images.
  if (job.calibration_views > 0)
    summary.calibration_images = RenderCalibrationImages(job, shot, out);
  summary.frames = range.count();
  summary.cameras = static_cast<int>(rig.cameras.size());
  summary.knots = truth.tracks.knots();
  for (const calib::Camera& camera : rig.cameras) summary.camera_names.push_back(camera.name);
  summary.knots_visible_mean = std::move(truth.knots_visible_mean);
  summary.knots_visible_min = std::move(truth.knots_visible_min);
  summary.render_s = render_s;
  folder.Commit();
  summary.wall_s = Seconds(start);
  return summary;
}

}  // namespace netlab::recon
