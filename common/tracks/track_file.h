#pragma once
// The knot-track file: the common currency of netlab. `netlab simulate` writes it, `netlab
// triangulate` writes it, `netlab score` reads two of them. This is its one reader and writer.
//
// Layout (HDF5; every dataset has a "units" attribute):
//   /time                         [T]        float64  s
//   /knots/position               [T,K,3]    float64  m, simulation/world frame
//   /knots/grid                   [K,2]      int32    (row, col) of each knot in its net
//   /knots/net                    [K]        int32    index of the knot's net (attribute "names")
//   /knots/valid                  [T,K]      uint8    1 where the position is known
//   /knots/covariance             [T,K,3,3]  float64  m^2       (optional: measured tracks)
//   /knots/reprojection_error_px  [T,K]      float64  px        (optional: measured tracks)
//   /frame_index                  [T]        int32    frame number of each row (optional)
//   /outliers/observation         [N,3]      int32    (frame number, knot index, camera index)
//   /outliers/residual_px         [N]        float64  px, NaN where no point was triangulated
//                                 (optional, measured tracks: observations left out; the group's
//                                 attribute "cameras" names the camera indices, one per line)
//   /knots/degenerate             [T,K]      uint8    1 where a point was triangulated but its rays
//                                 meet too close to parallel or head-on to place it (its largest
//                                 sigma over the bound): valid 0 there, position and covariance
//                                 kept (optional: measured tracks)
//   /degenerate/point             [N,2]      int32    (frame number, knot index) of each one
//   /degenerate/sigma_m           [N]        float64  m: its largest standard deviation
//   /degenerate/ray_angle_deg     [N]        float64  deg: the angle its best-crossing rays meet at
//   /degenerate/reason            string     one line per point, the reason in words
//   /degenerate/max_sigma_m       [1]        float64  m: the bound (attribute "from": how chosen)
//   /frame_time_spread_s          [T]        float64  s: per frame, the largest minus the smallest
//                                 of the cameras' timestamps (optional: measured tracks whose
//                                 /time is the cameras' mean timestamp)
//   /camera_offsets/frames        [C]        float64  frames: each camera's clock offset against
//                                 the reference (NaN: not determined)  (optional: measured tracks)
//   /camera_offsets/sigma_frames  [C]        float64  frames: its standard deviation; the group's
//                                 attributes "cameras" (names, one per line) and "applied"
//                                 ("yes": the labels were moved to the frame time, else "no")
//   /nodes/position               [T,N,3]    float64  m         (optional: simulations)
//   /probes/<name>                [T,3]      float64  m         (optional: simulations)
//   /scenario                     string     the scenario YAML  (optional: simulations)
//   /contact_start                [1]        float64  s: the first contact of the net with a
//                                 body (optional: simulations that had one)
// Root attributes: "format" = "netlab-knot-tracks", "version" = "1", "source" (the command).
// Files are written to "<path>.partial" and renamed into place when complete, so an interrupted
// write never replaces a good file.

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <limits>
#include <memory>
#include <string>
#include <vector>

namespace netlab {

inline constexpr char kTrackFileFormat[] = "netlab-knot-tracks";

struct KnotTracks {
  std::vector<double> time;                   // [T], s
  std::vector<std::array<int, 2>> grid;       // [K], (row, col)
  std::vector<int> net;                       // [K], net index; empty: every knot in net 0
  std::vector<std::string> net_names;         // names of the nets
  std::vector<Eigen::Vector3d> position;      // [T*K], frame-major: position[t * K + k], m
  std::vector<uint8_t> valid;                 // [T*K]
  std::vector<Eigen::Matrix3d> covariance;    // [T*K] m^2, or empty
  std::vector<double> reprojection_error_px;  // [T*K], or empty
  std::vector<int> frame_index;               // [T] frame numbers, or empty
  struct Outlier {
    int frame = 0, knot = 0, camera = 0;  // frame number, knot index, index into camera_names
    double residual_px = 0.0;
  };
  std::vector<Outlier> outliers;          // observations left out (measured tracks)
  std::vector<std::string> camera_names;  // non-empty: /outliers is written
  std::vector<uint8_t> degenerate;        // [T*K], or empty: /knots/degenerate
  struct Degenerate {
    int frame = 0, knot = 0;  // frame number, knot index
    double sigma_m = 0.0, ray_angle_deg = 0.0;
    std::string reason;  // one line
  };
  std::vector<Degenerate> degenerate_points;  // written with `degenerate`
  double degenerate_max_sigma_m = 0.0;
  std::string degenerate_bound_from;        // e.g. "10 x the median sigma (0.123 mm)"
  std::vector<double> frame_time_spread_s;  // [T], or empty
  // Per camera_names entry, or empty: /camera_offsets.
  std::vector<double> camera_offset_frames, camera_offset_sigma_frames;
  bool camera_offsets_applied = false;
  std::string source;    // e.g. "netlab simulate"
  std::string scenario;  // scenario YAML, or empty
  // s: the simulation's first contact of the net with a body; NaN: none (or not a simulation)
  double contact_start_s = std::numeric_limits<double>::quiet_NaN();

  int frames() const { return static_cast<int>(time.size()); }
  int knots() const { return static_cast<int>(grid.size()); }
  const Eigen::Vector3d& Position(int frame, int knot) const {
    return position[static_cast<size_t>(frame) * grid.size() + knot];
  }
  bool Valid(int frame, int knot) const {
    return valid[static_cast<size_t>(frame) * grid.size() + knot] != 0;
  }
  bool Degenerate(int frame, int knot) const {
    return !degenerate.empty() && degenerate[static_cast<size_t>(frame) * grid.size() + knot] != 0;
  }
  // Index of knot (row, col) of net `net`, or -1.
  int FindKnot(int row, int col, int net_index = 0) const;
  // Throws std::invalid_argument if the arrays disagree in size.
  void CheckConsistent() const;
};

// Writes `tracks` to `path` (via "<path>.partial" and a rename). Throws std::runtime_error.
void WriteKnotTracks(const std::string& path, const KnotTracks& tracks);

// Reads a knot-track file. Throws std::runtime_error naming the file and the dataset when the file
// is missing, not HDF5, not a knot-track file, or its datasets disagree in shape. A "units"
// attribute is honoured: /time and /contact_start in s, ms, us or ns, positions in m, cm, mm or
// um, covariances in m^2, cm^2 or mm^2 are converted to s, m and m^2; other units are refused by
// name (no attribute: the SI unit netlab writes).
KnotTracks ReadKnotTracks(const std::string& path);

// Node positions of a simulation file, [T][N], m (empty if the file has none; units as above).
std::vector<std::vector<Eigen::Vector3d>> ReadNodePositions(const std::string& path);

// Streams a simulation into a knot-track file, one frame at a time (a run may be longer than
// memory allows, and an interrupted one keeps what it wrote in "<path>.partial").
class TrackFileWriter {
 public:
  struct Layout {
    int nodes = 0;                         // node count, 0: no /nodes
    std::vector<std::array<int, 2>> grid;  // knots
    std::vector<int> net;                  // net index per knot
    std::vector<std::string> net_names;
    std::vector<std::string> probe_names;
    std::string source = "netlab simulate";
    std::string scenario;  // stored as /scenario when not empty
  };

  // Creates "<path>.partial". Throws std::runtime_error if it cannot.
  TrackFileWriter(const std::string& path, const Layout& layout);
  ~TrackFileWriter();
  TrackFileWriter(const TrackFileWriter&) = delete;
  TrackFileWriter& operator=(const TrackFileWriter&) = delete;

  // nodes: N positions (ignored when Layout::nodes is 0); knots: K positions; probes: one per
  // probe name. Every knot of a simulation is valid.
  void AppendFrame(double time, const std::vector<Eigen::Vector3d>& nodes,
                   const std::vector<Eigen::Vector3d>& knots,
                   const std::vector<Eigen::Vector3d>& probes);
  int frames() const { return frames_; }
  // The time of the net's first contact with a body, written as /contact_start at Commit.
  void SetContactStart(double time_s) { contact_start_s_ = time_s; }

  // Closes the file and renames it to `path`. Without Commit the partial file stays.
  void Commit();
  const std::string& partial_path() const { return partial_path_; }

 private:
  struct Handles;
  std::string path_;
  std::string partial_path_;
  Layout layout_;
  int frames_ = 0;
  std::unique_ptr<Handles> handles_;
  double contact_start_s_ = std::numeric_limits<double>::quiet_NaN();
};

}  // namespace netlab
