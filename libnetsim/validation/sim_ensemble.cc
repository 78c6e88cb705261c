#include "libnetsim/validation/sim_ensemble.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <map>
#include <sstream>

#include "common/errors.h"
#include "common/hdf5_util.h"
#include "common/memory.h"

namespace netlab::netsim {
namespace {

std::vector<std::string> SplitCommas(const std::string& text) {
  std::vector<std::string> parts;
  std::stringstream in(text);
  std::string part;
  while (std::getline(in, part, ','))
    if (!part.empty()) parts.push_back(part);
  return parts;
}

bool IsSweepFile(const std::string& path) {
  const h5::Id file = h5::OpenFileReadOnly(path);
  return h5::ReadStringAttribute(file.get(), "format") == "netlab-sweep";
}

// The runs of a sweep file that finished, each as knot tracks on the sweep's /knots/grid.
std::vector<EnsembleMember> ReadSweepMembers(const std::string& path) {
  std::lock_guard<std::mutex> lock(h5::Mutex());
  const h5::Id file = h5::OpenFileReadOnly(path);
  if (!h5::Exists(file.get(), "/knots/grid"))
    throw InputError(path + ": no /knots/grid: no run of this sweep built its net");
  const std::vector<hsize_t> gdims = h5::DatasetDims(file.get(), "/knots/grid");
  if (gdims.size() != 2 || gdims[1] != 2 || gdims[0] == 0)
    throw InputError(path + ": /knots/grid must be [K, 2] with K > 0");
  const int knots = static_cast<int>(gdims[0]);
  std::vector<std::array<int, 2>> grid(knots);
  h5::ReadDataset(file.get(), "/knots/grid", H5T_NATIVE_INT, grid.data());
  std::vector<int> net(knots, 0);
  if (h5::Exists(file.get(), "/knots/net"))
    h5::ReadDataset(file.get(), "/knots/net", H5T_NATIVE_INT, net.data());
  std::vector<EnsembleMember> members;
  double bytes = 0.0;  // what the members read so far take
  for (int i = 0;; ++i) {
    const std::string group = "/tracks/" + std::to_string(i);
    if (!h5::Exists(file.get(), group)) break;
    const h5::Id g(H5Gopen2(file.get(), group.c_str(), H5P_DEFAULT));
    if (h5::ReadStringAttribute(g.get(), "status") != "ok") continue;
    if (!h5::Exists(file.get(), group + "/knots/position")) continue;
    EnsembleMember m;
    m.name = path + ":" + group;
    KnotTracks& t = m.tracks;
    t.grid = grid;
    t.net = net;
    const std::vector<hsize_t> dims = h5::DatasetDims(file.get(), group + "/knots/position");
    if (dims.size() != 3 || static_cast<int>(dims[1]) != knots || dims[2] != 3)
      throw InputError(m.name + "/knots/position: not [T, " + std::to_string(knots) +
                       ", 3] as /knots/grid lists the knots");
    if (!h5::Exists(file.get(), group + "/time") ||
        h5::DatasetDims(file.get(), group + "/time") != std::vector<hsize_t>{dims[0]})
      throw InputError(m.name + "/time: missing or not [" + std::to_string(dims[0]) +
                       "] as its /knots/position's frames");
    // A dataset's extent costs nothing to declare: sized before anything is allocated (a
    // position and a flag per knot-frame, a time per frame; every member is kept).
    bytes += static_cast<double>(dims[0]) * (8.0 + knots * 25.0);
    if (const std::string shortfall = MemoryShortfall(bytes); !shortfall.empty())
      throw InputError(m.name + ": " + std::to_string(dims[0]) + " frames of " +
                       std::to_string(knots) +
                       " knots (with the members before it): reading them " + shortfall);
    t.time.resize(dims[0]);
    t.position.resize(dims[0] * knots);
    h5::ReadDataset(file.get(), group + "/time", H5T_NATIVE_DOUBLE, t.time.data());
    h5::ReadDataset(file.get(), group + "/knots/position", H5T_NATIVE_DOUBLE, t.position.data());
    // A unit the file states is converted or refused (h5::UnitsFactor), never ignored.
    const double to_s = h5::UnitsFactor(file.get(), path, group + "/time", h5::kSeconds);
    const double to_m = h5::UnitsFactor(file.get(), path, group + "/knots/position", h5::kMetres);
    for (double& time : t.time) time *= to_s;
    for (Eigen::Vector3d& p : t.position) p *= to_m;
    t.valid.assign(t.position.size(), 1);
    for (size_t j = 0; j < t.position.size(); ++j)
      if (!t.position[j].allFinite()) t.valid[j] = 0;
    members.push_back(std::move(m));
  }
  return members;
}

std::string Seconds(double t) {
  char text[32];
  std::snprintf(text, sizeof(text), "%.6g s", t);
  return text;
}

}  // namespace

std::vector<EnsembleMember> ReadEnsemble(const std::string& spec) {
  const std::vector<std::string> paths = SplitCommas(spec);
  if (paths.empty()) throw InputError("--sim-ensemble: no file given");
  if (paths.size() == 1 && IsSweepFile(paths[0])) return ReadSweepMembers(paths[0]);
  std::vector<EnsembleMember> members;
  for (const std::string& path : paths) {
    if (IsSweepFile(path))
      throw InputError(path + ": a sweep file in a list of simulation files: give it alone");
    members.push_back({path, ReadKnotTracks(path)});
  }
  return members;
}

KnotTracks AddEnsembleCovariance(const KnotTracks& sim, const std::string& sim_name,
                                 const std::vector<EnsembleMember>& members, double* max_sigma_m) {
  const int m_count = static_cast<int>(members.size());
  if (m_count < 2)
    throw InputError(std::string("--sim-ensemble: ") + std::to_string(m_count) +
                     (m_count == 1 ? " member (" + members[0].name + ")" : " members") +
                     ": a spread needs at least 2 runs");
  const int frames = sim.frames(), knots = sim.knots();
  std::map<std::array<int, 3>, int> index;  // (net, row, col) -> knot of the member
  // For every member, the member's knot of each simulated knot.
  std::vector<std::vector<int>> member_knot(m_count, std::vector<int>(knots, -1));
  for (int m = 0; m < m_count; ++m) {
    const KnotTracks& t = members[m].tracks;
    if (t.knots() != knots)
      throw InputError(members[m].name + ": " + std::to_string(t.knots()) + " knots, " + sim_name +
                       " has " + std::to_string(knots) +
                       ": an ensemble must be runs of the same net");
    index.clear();
    for (int k = 0; k < t.knots(); ++k)
      index[{t.net.empty() ? 0 : t.net[k], t.grid[k][0], t.grid[k][1]}] = k;
    for (int k = 0; k < knots; ++k) {
      const auto it =
          index.find({sim.net.empty() ? 0 : sim.net[k], sim.grid[k][0], sim.grid[k][1]});
      if (it == index.end())
        throw InputError(members[m].name + ": has no knot (" + std::to_string(sim.grid[k][0]) +
                         ", " + std::to_string(sim.grid[k][1]) + ") of " + sim_name +
                         ": an ensemble must be runs of the same net");
      member_knot[m][k] = it->second;
    }
    if (t.frames() < 2)
      throw InputError(members[m].name + ": " + std::to_string(t.frames()) +
                       " frames: a member must cover the simulation's time");
    // One member frame of slack at each end: a run of another step stores its frames at its
    // steps, and may end up to a frame early. A frame of the simulation beyond a member's span
    // takes the spread of the other members (no extrapolation).
    const double slack = 1.01 * (t.time.back() - t.time.front()) / (t.frames() - 1);
    if (t.time.front() > sim.time.front() + slack || t.time.back() < sim.time.back() - slack)
      throw InputError(members[m].name + ": covers [" + Seconds(t.time.front()) + ", " +
                       Seconds(t.time.back()) + "], " + sim_name + " [" +
                       Seconds(sim.time.front()) + ", " + Seconds(sim.time.back()) +
                       "]: a member must cover the simulation's time (a run that blew up or "
                       "stopped early?)");
  }
  KnotTracks out = sim;
  out.covariance.assign(static_cast<size_t>(frames) * knots, Eigen::Matrix3d::Zero());
  if (!sim.covariance.empty()) out.covariance = sim.covariance;
  double max_var = 0.0;
  std::vector<Eigen::Vector3d> samples(m_count);
  for (int f = 0; f < frames; ++f) {
    // Each member's bracketing frames and weight at the simulated time.
    std::vector<std::array<double, 3>> at(m_count);  // i0, i1, w1; i0 < 0: outside its span
    for (int m = 0; m < m_count; ++m) {
      const auto& time = members[m].tracks.time;
      if (sim.time[f] < time.front() - 1e-9 || sim.time[f] > time.back() + 1e-9) {
        at[m] = {-1.0, -1.0, 0.0};
        continue;
      }
      const double t = std::clamp(sim.time[f], time.front(), time.back());
      const int i1 =
          std::clamp(static_cast<int>(std::lower_bound(time.begin(), time.end(), t) - time.begin()),
                     1, static_cast<int>(time.size()) - 1);
      const double span = time[i1] - time[i1 - 1];
      at[m] = {static_cast<double>(i1 - 1), static_cast<double>(i1),
               span > 0 ? (t - time[i1 - 1]) / span : 0.0};
    }
    for (int k = 0; k < knots; ++k) {
      int n = 0;
      for (int m = 0; m < m_count; ++m) {
        const KnotTracks& t = members[m].tracks;
        const int a = static_cast<int>(at[m][0]), b = static_cast<int>(at[m][1]);
        if (a < 0) continue;
        const int mk = member_knot[m][k];
        if (!t.Valid(a, mk) || !t.Valid(b, mk)) continue;
        samples[n++] = (1 - at[m][2]) * t.Position(a, mk) + at[m][2] * t.Position(b, mk);
      }
      if (n < 2) continue;  // a knot lost in all but one member: no spread to state
      Eigen::Vector3d mean = Eigen::Vector3d::Zero();
      for (int i = 0; i < n; ++i) mean += samples[i];
      mean /= n;
      Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
      for (int i = 0; i < n; ++i) cov += (samples[i] - mean) * (samples[i] - mean).transpose();
      // The measured flight and the scored run are each one outcome of what the model cannot
      // know: their difference spreads twice as much as one run about the mean.
      // And r^T S^-1 r of a sample covariance of n - 1 degrees of freedom averages
      // 3 (n - 1) / (n - 5), not 3 (Hotelling): S is scaled by (n - 1) / (n - 5) so that a
      // phase the spread dominates expects 3 (no scale defined for n <= 5).
      cov *= 2.0 / (n - 1) * (n > 5 ? (n - 1.0) / (n - 5.0) : 1.0);
      out.covariance[static_cast<size_t>(f) * knots + k] += cov;
      max_var = std::max(max_var, cov.diagonal().maxCoeff());
    }
  }
  if (max_sigma_m) *max_sigma_m = std::sqrt(max_var);
  return out;
}

}  // namespace netlab::netsim
