#include "common/tracks/track_file.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <sstream>
#include <stdexcept>

#include "common/files.h"
#include "common/hdf5_util.h"
#include "common/memory.h"

namespace netlab {
namespace {

// /contact_start (s), when the simulation had a contact.
void WriteContactStart(hid_t file, double time_s) {
  if (!std::isfinite(time_s)) return;
  h5::WriteDataset(file, "contact_start", H5T_NATIVE_DOUBLE, {1}, &time_s);
  h5::SetUnits(file, "contact_start", "s");
}

void WriteRootAttributes(hid_t file, const std::string& source) {
  h5::WriteStringAttribute(file, "format", kTrackFileFormat);
  h5::WriteStringAttribute(file, "version", "1");
  h5::WriteStringAttribute(file, "source", source);
}

void WriteGrid(hid_t knots, const std::vector<std::array<int, 2>>& grid,
               const std::vector<int>& net, const std::vector<std::string>& net_names) {
  std::vector<int32_t> flat;
  for (const auto& g : grid) {
    flat.push_back(g[0]);
    flat.push_back(g[1]);
  }
  h5::WriteDataset(knots, "grid", H5T_NATIVE_INT32, {grid.size(), 2}, flat.data());
  h5::SetUnits(knots, "grid", "(row, col)");
  std::vector<int32_t> nets(grid.size(), 0);
  for (size_t k = 0; k < net.size() && k < nets.size(); ++k) nets[k] = net[k];
  h5::WriteDataset(knots, "net", H5T_NATIVE_INT32, {nets.size()}, nets.data());
  h5::SetUnits(knots, "net", "index");
  h5::Id dataset(H5Dopen2(knots, "net", H5P_DEFAULT));
  h5::WriteStringAttribute(dataset.get(), "names", h5::JoinLines(net_names));
}

// /knots/degenerate and the /degenerate group, when the tracks carry the flags.
void WriteDegenerate(hid_t file, hid_t knots, const KnotTracks& tracks) {
  if (tracks.degenerate.empty()) return;
  const hsize_t t = tracks.time.size(), k = tracks.grid.size(), n = tracks.degenerate_points.size();
  h5::WriteDataset(knots, "degenerate", H5T_NATIVE_UINT8, {t, k}, tracks.degenerate.data(), 4);
  h5::SetUnits(knots, "degenerate", "1");
  h5::Id group = h5::CreateGroup(file, "degenerate");
  std::vector<int32_t> point;
  std::vector<double> sigma, angle;
  std::vector<std::string> reasons;
  for (const auto& d : tracks.degenerate_points) {
    point.insert(point.end(), {d.frame, d.knot});
    sigma.push_back(d.sigma_m);
    angle.push_back(d.ray_angle_deg);
    reasons.push_back(d.reason);
  }
  if (n > 0) {  // (an empty dataset is not written: the bound and the flags say it all)
    h5::WriteDataset(group.get(), "point", H5T_NATIVE_INT32, {n, 2}, point.data());
    h5::SetUnits(group.get(), "point", "(frame, knot)");
    h5::WriteDataset(group.get(), "sigma_m", H5T_NATIVE_DOUBLE, {n}, sigma.data());
    h5::SetUnits(group.get(), "sigma_m", "m");
    h5::WriteDataset(group.get(), "ray_angle_deg", H5T_NATIVE_DOUBLE, {n}, angle.data());
    h5::SetUnits(group.get(), "ray_angle_deg", "deg");
    h5::WriteStringDataset(group.get(), "reason", h5::JoinLines(reasons));
  }
  h5::WriteDataset(group.get(), "max_sigma_m", H5T_NATIVE_DOUBLE, {1},
                   &tracks.degenerate_max_sigma_m);
  h5::SetUnits(group.get(), "max_sigma_m", "m");
  h5::Id bound(H5Dopen2(group.get(), "max_sigma_m", H5P_DEFAULT));
  h5::WriteStringAttribute(bound.get(), "from", tracks.degenerate_bound_from);
}

// /frame_time_spread_s and /camera_offsets, when the tracks carry them.
void WriteClocks(hid_t file, const KnotTracks& tracks) {
  if (!tracks.frame_time_spread_s.empty()) {
    h5::WriteDataset(file, "frame_time_spread_s", H5T_NATIVE_DOUBLE, {tracks.time.size()},
                     tracks.frame_time_spread_s.data());
    h5::SetUnits(file, "frame_time_spread_s", "s");
  }
  if (tracks.camera_offset_frames.empty()) return;
  const hsize_t c = tracks.camera_offset_frames.size();
  h5::Id group = h5::CreateGroup(file, "camera_offsets");
  h5::WriteStringAttribute(group.get(), "cameras", h5::JoinLines(tracks.camera_names));
  h5::WriteStringAttribute(group.get(), "applied", tracks.camera_offsets_applied ? "yes" : "no");
  h5::WriteDataset(group.get(), "frames", H5T_NATIVE_DOUBLE, {c},
                   tracks.camera_offset_frames.data());
  h5::SetUnits(group.get(), "frames", "frames");
  h5::WriteDataset(group.get(), "sigma_frames", H5T_NATIVE_DOUBLE, {c},
                   tracks.camera_offset_sigma_frames.data());
  h5::SetUnits(group.get(), "sigma_frames", "frames");
}

}  // namespace

int KnotTracks::FindKnot(int row, int col, int net_index) const {
  for (size_t k = 0; k < grid.size(); ++k) {
    const int n = net.empty() ? 0 : net[k];
    if (grid[k][0] == row && grid[k][1] == col && n == net_index) return static_cast<int>(k);
  }
  return -1;
}

void KnotTracks::CheckConsistent() const {
  const size_t cells = time.size() * grid.size();
  auto fail = [](const std::string& what) { throw std::invalid_argument("knot tracks: " + what); };
  if (position.size() != cells) fail("position must hold frames x knots entries");
  if (valid.size() != cells) fail("valid must hold frames x knots entries");
  if (!net.empty() && net.size() != grid.size()) fail("net must hold one entry per knot");
  if (!covariance.empty() && covariance.size() != cells) fail("covariance size");
  if (!reprojection_error_px.empty() && reprojection_error_px.size() != cells)
    fail("reprojection_error_px size");
  if (!frame_index.empty() && frame_index.size() != time.size()) fail("frame_index size");
  if (!degenerate.empty() && degenerate.size() != cells) fail("degenerate size");
  if (!frame_time_spread_s.empty() && frame_time_spread_s.size() != time.size())
    fail("frame_time_spread_s size");
  if ((!camera_offset_frames.empty() && camera_offset_frames.size() != camera_names.size()) ||
      camera_offset_sigma_frames.size() != camera_offset_frames.size())
    fail("camera offsets must hold one entry per camera name");
  for (const Outlier& o : outliers)
    if (o.camera < 0 || o.camera >= static_cast<int>(camera_names.size()) || o.knot < 0 ||
        o.knot >= static_cast<int>(grid.size()))
      fail("an outlier names a camera or knot that does not exist");
}

void WriteKnotTracks(const std::string& path, const KnotTracks& tracks) {
  tracks.CheckConsistent();
  const std::string partial = path + ".partial";
  {
    h5::Id file = h5::CreateFile(partial);
    WriteRootAttributes(file.get(), tracks.source);
    const hsize_t t = tracks.time.size(), k = tracks.grid.size();
    h5::WriteDataset(file.get(), "time", H5T_NATIVE_DOUBLE, {t}, tracks.time.data());
    h5::SetUnits(file.get(), "time", "s");
    h5::Id knots = h5::CreateGroup(file.get(), "knots");
    WriteGrid(knots.get(), tracks.grid, tracks.net, tracks.net_names);
    h5::WriteDataset(knots.get(), "position", H5T_NATIVE_DOUBLE, {t, k, 3}, tracks.position.data(),
                     4);
    h5::SetUnits(knots.get(), "position", "m");
    h5::WriteDataset(knots.get(), "valid", H5T_NATIVE_UINT8, {t, k}, tracks.valid.data(), 4);
    h5::SetUnits(knots.get(), "valid", "1");
    if (!tracks.covariance.empty()) {
      h5::WriteDataset(knots.get(), "covariance", H5T_NATIVE_DOUBLE, {t, k, 3, 3},
                       tracks.covariance.data(), 4);
      h5::SetUnits(knots.get(), "covariance", "m^2");
    }
    if (!tracks.reprojection_error_px.empty()) {
      h5::WriteDataset(knots.get(), "reprojection_error_px", H5T_NATIVE_DOUBLE, {t, k},
                       tracks.reprojection_error_px.data(), 4);
      h5::SetUnits(knots.get(), "reprojection_error_px", "px");
    }
    if (!tracks.frame_index.empty()) {
      std::vector<int32_t> frames(tracks.frame_index.begin(), tracks.frame_index.end());
      h5::WriteDataset(file.get(), "frame_index", H5T_NATIVE_INT32, {t}, frames.data());
      h5::SetUnits(file.get(), "frame_index", "index");
    }
    if (!tracks.camera_names.empty()) {
      h5::Id outliers = h5::CreateGroup(file.get(), "outliers");
      h5::WriteStringAttribute(outliers.get(), "cameras", h5::JoinLines(tracks.camera_names));
      if (!tracks.outliers.empty()) {
        const hsize_t n = tracks.outliers.size();
        std::vector<int32_t> obs;
        std::vector<double> residual;
        for (const auto& o : tracks.outliers) {
          obs.insert(obs.end(), {o.frame, o.knot, o.camera});
          residual.push_back(o.residual_px);
        }
        h5::WriteDataset(outliers.get(), "observation", H5T_NATIVE_INT32, {n, 3}, obs.data());
        h5::SetUnits(outliers.get(), "observation", "(frame, knot, camera)");
        h5::WriteDataset(outliers.get(), "residual_px", H5T_NATIVE_DOUBLE, {n}, residual.data());
        h5::SetUnits(outliers.get(), "residual_px", "px");
      }
    }
    WriteDegenerate(file.get(), knots.get(), tracks);
    WriteClocks(file.get(), tracks);
    if (!tracks.scenario.empty()) h5::WriteStringDataset(file.get(), "scenario", tracks.scenario);
    WriteContactStart(file.get(), tracks.contact_start_s);
    H5Fflush(file.get(), H5F_SCOPE_GLOBAL);
  }
  RenameInto(partial, path);
}

namespace {

void ExpectDims(hid_t f, const std::string& path, const std::string& name,
                const std::vector<hsize_t>& dims) {
  if (h5::DatasetDims(f, name) == dims) return;
  std::string shape;
  for (hsize_t d : dims) shape += (shape.empty() ? "" : ",") + std::to_string(d);
  throw std::runtime_error(path + ": " + name + " must have shape [" + shape + "]");
}

void ReadDegenerate(hid_t f, const std::string& path, KnotTracks* tracks) {
  if (!h5::Exists(f, "/knots/degenerate")) return;
  const hsize_t t = tracks->time.size(), k = tracks->grid.size();
  ExpectDims(f, path, "/knots/degenerate", {t, k});
  tracks->degenerate.resize(t * k);
  h5::ReadDataset(f, "/knots/degenerate", H5T_NATIVE_UINT8, tracks->degenerate.data());
  if (h5::Exists(f, "/degenerate/max_sigma_m")) {
    ExpectDims(f, path, "/degenerate/max_sigma_m", {1});
    h5::ReadDataset(f, "/degenerate/max_sigma_m", H5T_NATIVE_DOUBLE,
                    &tracks->degenerate_max_sigma_m);
    h5::Id bound(H5Dopen2(f, "/degenerate/max_sigma_m", H5P_DEFAULT));
    tracks->degenerate_bound_from = h5::ReadStringAttribute(bound.get(), "from");
  }
  if (!h5::Exists(f, "/degenerate/point")) return;
  const auto dims = h5::DatasetDims(f, "/degenerate/point");
  if (dims.size() != 2 || dims[1] != 2)
    throw std::runtime_error(path + ": /degenerate/point must be [N,2]");
  const hsize_t n = dims[0];
  ExpectDims(f, path, "/degenerate/sigma_m", {n});
  ExpectDims(f, path, "/degenerate/ray_angle_deg", {n});
  std::vector<int32_t> point(2 * n);
  std::vector<double> sigma(n), angle(n);
  h5::ReadDataset(f, "/degenerate/point", H5T_NATIVE_INT32, point.data());
  h5::ReadDataset(f, "/degenerate/sigma_m", H5T_NATIVE_DOUBLE, sigma.data());
  h5::ReadDataset(f, "/degenerate/ray_angle_deg", H5T_NATIVE_DOUBLE, angle.data());
  std::vector<std::string> reasons;
  if (h5::Exists(f, "/degenerate/reason"))
    reasons = h5::SplitLines(h5::ReadStringDataset(f, "/degenerate/reason"));
  for (hsize_t i = 0; i < n; ++i)
    tracks->degenerate_points.push_back(
        {point[2 * i], point[2 * i + 1], sigma[i], angle[i], i < reasons.size() ? reasons[i] : ""});
}

void ReadClocks(hid_t f, const std::string& path, KnotTracks* tracks) {
  if (h5::Exists(f, "/frame_time_spread_s")) {
    ExpectDims(f, path, "/frame_time_spread_s", {tracks->time.size()});
    tracks->frame_time_spread_s.resize(tracks->time.size());
    h5::ReadDataset(f, "/frame_time_spread_s", H5T_NATIVE_DOUBLE,
                    tracks->frame_time_spread_s.data());
  }
  if (!h5::Exists(f, "/camera_offsets/frames")) return;
  h5::Id group(H5Gopen2(f, "/camera_offsets", H5P_DEFAULT));
  const std::vector<std::string> names =
      h5::SplitLines(h5::ReadStringAttribute(group.get(), "cameras"));
  if (!tracks->camera_names.empty() && names != tracks->camera_names)
    throw std::runtime_error(path + ": /camera_offsets names other cameras than /outliers");
  tracks->camera_names = names;
  ExpectDims(f, path, "/camera_offsets/frames", {names.size()});
  ExpectDims(f, path, "/camera_offsets/sigma_frames", {names.size()});
  tracks->camera_offset_frames.resize(names.size());
  tracks->camera_offset_sigma_frames.resize(names.size());
  h5::ReadDataset(f, "/camera_offsets/frames", H5T_NATIVE_DOUBLE,
                  tracks->camera_offset_frames.data());
  h5::ReadDataset(f, "/camera_offsets/sigma_frames", H5T_NATIVE_DOUBLE,
                  tracks->camera_offset_sigma_frames.data());
  tracks->camera_offsets_applied = h5::ReadStringAttribute(group.get(), "applied") == "yes";
}

}  // namespace

KnotTracks ReadKnotTracks(const std::string& path) {
  h5::Id file = h5::OpenFileReadOnly(path);
  const hid_t f = file.get();
  auto fail = [&](const std::string& what) { throw std::runtime_error(path + ": " + what); };
  const std::string format = h5::ReadStringAttribute(f, "format");
  if (format != kTrackFileFormat)
    fail("not a knot-track file (root attribute format is '" + format + "', expected '" +
         kTrackFileFormat + "')");
  for (const char* name : {"/time", "/knots/position", "/knots/grid", "/knots/valid"})
    if (!h5::Exists(f, name)) fail(std::string("missing dataset ") + name);

  KnotTracks tracks;
  tracks.source = h5::ReadStringAttribute(f, "source");
  const auto time_dims = h5::DatasetDims(f, "/time");
  const auto grid_dims = h5::DatasetDims(f, "/knots/grid");
  if (time_dims.size() != 1) fail("/time must be 1-D");
  if (grid_dims.size() != 2 || grid_dims[1] != 2) fail("/knots/grid must be [K,2]");
  const hsize_t t = time_dims[0], k = grid_dims[0];
  // A dataset's extent costs nothing to declare: a file of 1e11 frames is 3 kB, and reading it
  // ended in a bare "out of memory". Sized before anything is allocated (a position, a flag and a
  // covariance per knot-frame, a time per frame).
  if (const std::string shortfall =
          MemoryShortfall(static_cast<double>(t) * (8.0 + static_cast<double>(k) * 97.0));
      !shortfall.empty())
    fail("/time and /knots/grid give " + std::to_string(t) + " frames of " + std::to_string(k) +
         " knots: reading them " + shortfall);
  auto expect = [&](const char* name, std::vector<hsize_t> dims) {
    if (h5::DatasetDims(f, name) != dims) {
      std::string shape;
      for (hsize_t d : dims) {
        if (!shape.empty()) shape += ',';
        shape += std::to_string(d);
      }
      fail(std::string(name) + " must have shape [" + shape + "] to match /time and /knots/grid");
    }
  };
  expect("/knots/position", {t, k, 3});
  expect("/knots/valid", {t, k});

  tracks.time.resize(t);
  h5::ReadDataset(f, "/time", H5T_NATIVE_DOUBLE, tracks.time.data());
  if (const double to_s = h5::UnitsFactor(f, path, "/time", h5::kSeconds); to_s != 1.0)
    for (double& time : tracks.time) time *= to_s;
  // A time that stands still or runs back (a decreasing /time read as "frames 0:-8") is refused
  // here, for every reader: render, triangulate --truth, score.
  for (hsize_t i = 0; i < t; ++i) {
    if (!std::isfinite(tracks.time[i])) fail("/time[" + std::to_string(i) + "] is not a number");
    if (i > 0 && !(tracks.time[i] > tracks.time[i - 1])) {
      std::ostringstream os;
      os << "/time is not increasing at row " << i << " (" << tracks.time[i - 1] << " s then "
         << tracks.time[i] << " s)";
      fail(os.str());
    }
  }
  std::vector<int32_t> grid(2 * k);
  h5::ReadDataset(f, "/knots/grid", H5T_NATIVE_INT32, grid.data());
  for (hsize_t i = 0; i < k; ++i) tracks.grid.push_back({grid[2 * i], grid[2 * i + 1]});
  if (h5::Exists(f, "/knots/net")) {
    expect("/knots/net", {k});
    tracks.net.resize(k);
    h5::ReadDataset(f, "/knots/net", H5T_NATIVE_INT32, tracks.net.data());
    h5::Id dataset(H5Dopen2(f, "/knots/net", H5P_DEFAULT));
    tracks.net_names = h5::SplitLines(h5::ReadStringAttribute(dataset.get(), "names"));
  }
  tracks.position.resize(t * k);
  h5::ReadDataset(f, "/knots/position", H5T_NATIVE_DOUBLE, tracks.position.data());
  if (const double to_m = h5::UnitsFactor(f, path, "/knots/position", h5::kMetres); to_m != 1.0)
    for (Eigen::Vector3d& p : tracks.position) p *= to_m;
  tracks.valid.resize(t * k);
  h5::ReadDataset(f, "/knots/valid", H5T_NATIVE_UINT8, tracks.valid.data());
  for (hsize_t i = 0; i < t * k; ++i)
    if (tracks.valid[i] && !tracks.position[i].allFinite())
      fail("/knots/position is not finite at frame " + std::to_string(i / k) + ", knot (" +
           std::to_string(tracks.grid[i % k][0]) + "," + std::to_string(tracks.grid[i % k][1]) +
           "), where /knots/valid is 1");
  if (h5::Exists(f, "/knots/covariance")) {
    expect("/knots/covariance", {t, k, 3, 3});
    tracks.covariance.resize(t * k);
    h5::ReadDataset(f, "/knots/covariance", H5T_NATIVE_DOUBLE, tracks.covariance.data());
    if (const double to_m2 = h5::UnitsFactor(f, path, "/knots/covariance", h5::kSquareMetres);
        to_m2 != 1.0)
      for (Eigen::Matrix3d& c : tracks.covariance) c *= to_m2;
  }
  if (h5::Exists(f, "/knots/reprojection_error_px")) {
    expect("/knots/reprojection_error_px", {t, k});
    tracks.reprojection_error_px.resize(t * k);
    h5::ReadDataset(f, "/knots/reprojection_error_px", H5T_NATIVE_DOUBLE,
                    tracks.reprojection_error_px.data());
  }
  if (h5::Exists(f, "/frame_index")) {
    expect("/frame_index", {t});
    std::vector<int32_t> frames(t);
    h5::ReadDataset(f, "/frame_index", H5T_NATIVE_INT32, frames.data());
    for (hsize_t i = 0; i < t; ++i)
      if (frames[i] < 0 || (i > 0 && frames[i] <= frames[i - 1]))
        fail("/frame_index[" + std::to_string(i) + "] = " + std::to_string(frames[i]) +
             (frames[i] < 0 ? " is negative"
                            : " is not after [" + std::to_string(i - 1) +
                                  "] = " + std::to_string(frames[i - 1])));
    tracks.frame_index.assign(frames.begin(), frames.end());
  }
  if (h5::Exists(f, "/outliers")) {
    h5::Id group(H5Gopen2(f, "/outliers", H5P_DEFAULT));
    tracks.camera_names = h5::SplitLines(h5::ReadStringAttribute(group.get(), "cameras"));
    if (h5::Exists(f, "/outliers/observation")) {
      const auto dims = h5::DatasetDims(f, "/outliers/observation");
      if (dims.size() != 2 || dims[1] != 3) fail("/outliers/observation must be [N,3]");
      expect("/outliers/residual_px", {dims[0]});
      std::vector<int32_t> obs(3 * dims[0]);
      std::vector<double> residual(dims[0]);
      h5::ReadDataset(f, "/outliers/observation", H5T_NATIVE_INT32, obs.data());
      h5::ReadDataset(f, "/outliers/residual_px", H5T_NATIVE_DOUBLE, residual.data());
      for (hsize_t i = 0; i < dims[0]; ++i)
        tracks.outliers.push_back({obs[3 * i], obs[3 * i + 1], obs[3 * i + 2], residual[i]});
    }
  }
  ReadDegenerate(f, path, &tracks);
  ReadClocks(f, path, &tracks);
  if (h5::Exists(f, "/scenario")) tracks.scenario = h5::ReadStringDataset(f, "/scenario");
  if (h5::Exists(f, "/contact_start")) {
    if (h5::DatasetDims(f, "/contact_start") != std::vector<hsize_t>{1})
      fail("/contact_start must hold one time (s)");
    h5::ReadDataset(f, "/contact_start", H5T_NATIVE_DOUBLE, &tracks.contact_start_s);
    tracks.contact_start_s *= h5::UnitsFactor(f, path, "/contact_start", h5::kSeconds);
  }
  return tracks;
}

std::vector<std::vector<Eigen::Vector3d>> ReadNodePositions(const std::string& path) {
  h5::Id file = h5::OpenFileReadOnly(path);
  std::vector<std::vector<Eigen::Vector3d>> frames;
  if (!h5::Exists(file.get(), "/nodes/position")) return frames;
  const auto dims = h5::DatasetDims(file.get(), "/nodes/position");
  if (dims.size() != 3 || dims[2] != 3)
    throw std::runtime_error(path + ": /nodes/position must be [T,N,3]");
  std::vector<Eigen::Vector3d> flat(dims[0] * dims[1]);
  h5::ReadDataset(file.get(), "/nodes/position", H5T_NATIVE_DOUBLE, flat.data());
  if (const double to_m = h5::UnitsFactor(file.get(), path, "/nodes/position", h5::kMetres);
      to_m != 1.0)
    for (Eigen::Vector3d& p : flat) p *= to_m;
  for (hsize_t i = 0; i < dims[0]; ++i)
    frames.emplace_back(flat.begin() + i * dims[1], flat.begin() + (i + 1) * dims[1]);
  return frames;
}

struct TrackFileWriter::Handles {
  h5::Id file, time, knots, valid, nodes;
  std::vector<h5::Id> probes;
};

TrackFileWriter::TrackFileWriter(const std::string& path, const Layout& layout)
    : path_(path),
      partial_path_(path + ".partial"),
      layout_(layout),
      handles_(std::make_unique<Handles>()) {
  Handles& h = *handles_;
  h.file = h5::CreateFile(partial_path_);
  const hid_t f = h.file.get();
  WriteRootAttributes(f, layout.source);
  const hsize_t k = layout.grid.size();
  // ~64 frames per chunk for small nets, fewer for big ones (chunks of at most ~1 MB).
  const hsize_t per_frame = std::max<hsize_t>({k, static_cast<hsize_t>(layout.nodes), 1}) * 24;
  const hsize_t chunk = std::clamp<hsize_t>((1u << 20) / per_frame, 1, 64);
  h.time = h5::CreateFrameDataset(f, "time", H5T_NATIVE_DOUBLE, {}, 256);
  h5::SetUnits(f, "time", "s");
  h5::Id knots_group = h5::CreateGroup(f, "knots");
  WriteGrid(knots_group.get(), layout.grid, layout.net, layout.net_names);
  h.knots = h5::CreateFrameDataset(knots_group.get(), "position", H5T_NATIVE_DOUBLE, {k, 3}, chunk);
  h5::SetUnits(knots_group.get(), "position", "m");
  h.valid = h5::CreateFrameDataset(knots_group.get(), "valid", H5T_NATIVE_UINT8, {k}, chunk);
  h5::SetUnits(knots_group.get(), "valid", "1");
  if (layout.nodes > 0) {
    h5::Id nodes_group = h5::CreateGroup(f, "nodes");
    h.nodes = h5::CreateFrameDataset(nodes_group.get(), "position", H5T_NATIVE_DOUBLE,
                                     {static_cast<hsize_t>(layout.nodes), 3}, chunk);
    h5::SetUnits(nodes_group.get(), "position", "m");
  }
  if (!layout.probe_names.empty()) {
    h5::Id probes_group = h5::CreateGroup(f, "probes");
    for (const std::string& name : layout.probe_names) {
      h.probes.push_back(
          h5::CreateFrameDataset(probes_group.get(), name, H5T_NATIVE_DOUBLE, {3}, 256));
      h5::SetUnits(probes_group.get(), name, "m");
    }
  }
  if (!layout.scenario.empty()) h5::WriteStringDataset(f, "scenario", layout.scenario);
}

TrackFileWriter::~TrackFileWriter() = default;

void TrackFileWriter::AppendFrame(double time, const std::vector<Eigen::Vector3d>& nodes,
                                  const std::vector<Eigen::Vector3d>& knots,
                                  const std::vector<Eigen::Vector3d>& probes) {
  if (!handles_) throw std::logic_error("TrackFileWriter: AppendFrame after Commit");
  if (knots.size() != layout_.grid.size() || probes.size() != layout_.probe_names.size() ||
      (layout_.nodes > 0 && static_cast<int>(nodes.size()) != layout_.nodes))
    throw std::invalid_argument("TrackFileWriter: frame does not match the layout");
  Handles& h = *handles_;
  const hsize_t frame = static_cast<hsize_t>(frames_);
  h5::AppendFrame(h.time.get(), H5T_NATIVE_DOUBLE, &time, frame);
  h5::AppendFrame(h.knots.get(), H5T_NATIVE_DOUBLE, knots.data(), frame);
  const std::vector<uint8_t> valid(knots.size(), 1);
  h5::AppendFrame(h.valid.get(), H5T_NATIVE_UINT8, valid.data(), frame);
  if (layout_.nodes > 0) h5::AppendFrame(h.nodes.get(), H5T_NATIVE_DOUBLE, nodes.data(), frame);
  for (size_t p = 0; p < probes.size(); ++p)
    h5::AppendFrame(h.probes[p].get(), H5T_NATIVE_DOUBLE, probes[p].data(), frame);
  ++frames_;
}

void TrackFileWriter::Commit() {
  if (!handles_) return;
  WriteContactStart(handles_->file.get(), contact_start_s_);
  H5Fflush(handles_->file.get(), H5F_SCOPE_GLOBAL);
  handles_.reset();
  RenameInto(partial_path_, path_);
}

}  // namespace netlab
