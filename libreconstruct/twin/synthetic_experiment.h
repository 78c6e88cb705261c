#pragma once
// The synthetic experiment: a simulated shot filmed by a virtual copy of the camera rig, with its
// ground truth, so every later step (calibration, labeling, triangulation, scoring) can be tested
// against known answers before flight data exists.
//
//   RenderJob job;
//   job.simulation = "result.h5";      // `netlab simulate` output (with /nodes and /scenario)
//   job.out_dir = "synthetic";
//   job.rig = calib::PaperRig(0.5);
//   RenderSummary s = RenderExperiment(job, progress);
//
// Output in out_dir:
//   experiment.yaml                 read by `netlab ingest` (frames, Bayer pattern, timestamps)
//   <camera>/frame_%06d.pgm         raw Bayer mosaics (8 bit, or 16-bit words for 10..16 bits)
//   <camera>/timestamps.csv         frame_index,time_s
//   rig_true.yaml                   the rig the frames were rendered with
//   calibration/<camera>/view_%03d.png, calibration/foil.yaml   the checker foil at varied poses
//   truth.h5                        the knot-track layout of the simulator at the frame times, plus
//     /frame_index                  [T] int32, the camera frame of each row
//     /cameras/<camera>/knots_px    [T,K,2] float64, true pixel of each knot (OpenCV convention)
//     /cameras/<camera>/visibility  [T,K] uint8: 0 visible, 1 occluded by a solid (target body,
//                                   corner mass), 2 out of view (outside the image or behind)
//     /rig                          string, the rig file's text
//     /camera_time_offset_frames    [C] float64, each camera's clock offset in frames (the
//                                   group's cameras in the rig's order; attribute "cameras")
//     /cameras/<camera>/cam_from_world_rotation  [T,3,3], cam_from_world_translation [T,3]:
//                                   the camera's pose at each row's frame (its own clock)
//     /cameras/<camera>/response/   the camera's response (white_balance [3] B,G,R, gain,
//                                   gamma, prnu, dsnu, hot_pixels, pattern_seed)
//     /effects                      string, the effects the frames were filmed with (YAML)
//
// Frame k is the camera frame at time k / fps of the simulation; its exposure is centred there
// (motion blur samples the interval), and its truth is the state at that time. A camera with a
// clock offset d (RenderJob::camera_time_offset_frames) exposes its frame k at (k + d) / fps
// instead, as a trigger delay would: its timestamps still read k / fps, its true pixels
// (/cameras/<camera>/knots_px, labels_true.h5) are where it saw the knots, and the true tracks
// stay at the frame times.

#include <functional>
#include <string>
#include <vector>

#include "calibration/rig.h"
#include "common/progress.h"
#include "common/tracks/track_file.h"
#include "libnetsim/scenario/scenario.h"
#include "libreconstruct/coloring/palette.h"
#include "libreconstruct/coloring/yarn_coloring.h"
#include "libreconstruct/twin/flight_effects.h"
#include "libreconstruct/twin/render.h"

namespace netlab::recon {

// The scene content of a simulation: topology and bodies from its stored scenario, node motion
// from its frames.
class SimulatedShot {
 public:
  // Reads `path` (a `netlab simulate` file); InputError naming the file when it has no /nodes or
  // no /scenario, or naming the frame and node of a node position that is not finite.
  explicit SimulatedShot(const std::string& path);

  double start_time() const { return tracks_.time.front(); }
  double end_time() const { return tracks_.time.back(); }
  const KnotTracks& tracks() const { return tracks_; }
  const netsim::Model& model() const { return *model_; }

  // Node positions at time t (linear between stored frames, clamped to the stored range).
  std::vector<Eigen::Vector3d> NodesAt(double t) const;
  // Knot positions at time t, in the track file's knot order.
  std::vector<Eigen::Vector3d> KnotsAt(const std::vector<Eigen::Vector3d>& nodes) const;
  // The scene at time t, threads coloured per link by `coloring` (one per net; missing: default).
  Scene SceneAt(double t, const std::vector<YarnColoring>& coloring, Colour background) const;
  // Solids (target bodies, corner masses) at time t, with the nodes at t: what can hide a knot.
  Scene SolidsAt(double t, const std::vector<Eigen::Vector3d>& nodes) const;

 private:
  // InputError naming the file, the frame, its time and the node of the first non-finite node
  // position.
  void CheckFinite(const std::string& path) const;

  KnotTracks tracks_;
  std::vector<std::vector<Eigen::Vector3d>> nodes_;  // [T][N]
  netsim::Scenario scenario_;
  std::unique_ptr<netsim::Model> model_;
  std::vector<int> knot_nodes_;  // node of each track-file knot
  std::vector<int> corner_nodes_;
  std::vector<double> corner_radius_;
  std::vector<double> knot_radius_;  // per net: 0 for knotless
};

struct RenderJob {
  std::string simulation;  // `netlab simulate` HDF5
  std::string out_dir;
  calib::Rig rig;
  int first_frame = 0;
  int last_frame = -1;  // -1: the last frame the simulation covers
  double fps = 179.0;
  double exposure_s = 1e-3;  // motion blur interval, centred on the frame time
  int blur_samples = 3;      // renders averaged over the exposure
  SensorOptions sensor;      // Bayer pattern, bit depth, noise, vignetting
  Colour background{0.f, 0.f, 0.f};
  double illumination = kRenderIllumination;  // scene white in sensor units (palette.h)
  std::vector<YarnColoring> coloring;         // per net; empty: DefaultColoring
  std::string coloring_file;                  // where `coloring` was read from, for messages
  int calibration_views = 20;  // foil poses seen by all cameras (0: no calibration images)
  // Per rig camera: its clock offset, frames, -1 < d < 1 (empty: all 0).
  std::vector<double> camera_time_offset_frames;
  // The flight's acquisition effects (flight_effects.h), all off by default.
  LampRig lamps;                            // point lamps (empty: the directional light)
  bool paper_lamps = false;                 // lamps: PaperLamps of the rig (set when rendering)
  Flicker flicker;                          // the light's intensity over time
  DepthOfField depth_of_field;              // the thin lens (the same for every camera)
  std::vector<CameraResponse> responses;    // per rig camera (empty: the ideal sensor)
  bool textile_background = false;          // a textile panel instead of `background`
  bool background_clutter = false;          // the rig's structure along the frame's edges
  std::vector<CameraMotion> camera_motion;  // per rig camera (empty: all still)
  int threads = 2;
};

struct RenderSummary {
  int frames = 0;
  int cameras = 0;
  int knots = 0;
  std::vector<std::string> camera_names;
  std::vector<double> knots_visible_mean;  // per camera: visible knots per frame, mean
  std::vector<int> knots_visible_min;
  int calibration_images = 0;
  double wall_s = 0.0;
  double render_s = 0.0;  // of which rendering the frames
};

// InputError when `input` (a file the job reads, given as `option`) is inside `out_dir`, which
// RenderExperiment replaces as a whole: rendering next to the simulation would delete it.
void CheckOutsideOutput(const std::string& input, const std::string& option,
                        const std::string& out_dir);

// Renders the experiment (frames, truth, calibration images) into job.out_dir.partial, then puts
// it in place of job.out_dir (common/files.h FolderReplacement): a failing run leaves an existing
// out_dir as it was and removes its partial folder; every input is checked before any output.
// Progress: stage "frames rendered" (of all cameras), from any of the threads (one at a time); a
// cancel stops them between frames and throws Cancelled (the partial folder removed).
RenderSummary RenderExperiment(const RenderJob& job, const ProgressReporter& progress = {});

// A rig with every camera's image scaled by `scale` (focal lengths, principal point, size).
calib::Rig ScaleRig(const calib::Rig& rig, double scale);

// The visibility code of a knot for a camera: 0 visible, 1 hidden behind one of `solids`,
// 2 outside the image or behind the camera. `ignore_radius`: solids whose centre lies this close
// to the knot (its own corner mass) do not hide it.
uint8_t KnotVisibility(const calib::Camera& camera, const Eigen::Vector3d& knot,
                       const Scene& solids, double ignore_radius = 1e-6);

}  // namespace netlab::recon
