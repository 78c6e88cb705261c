#include "libreconstruct/geometry/track_export.h"

#include <Eigen/Cholesky>
#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <map>
#include <optional>
#include <regex>
#include <stdexcept>

#include "common/errors.h"
#include "libreconstruct/labels/csv_table.h"

namespace netlab::recon {
namespace {

// Linear interpolation of the truth's knot `k` at time t; false outside its time span or where
// either neighbouring sample is not valid.
bool TruthAt(const KnotTracks& truth, int k, double t, Eigen::Vector3d* p) {
  const auto& time = truth.time;
  if (time.empty() || t < time.front() - 1e-9 || t > time.back() + 1e-9) return false;
  const size_t hi = std::min<size_t>(time.size() - 1,
                                     std::lower_bound(time.begin(), time.end(), t) - time.begin());
  const size_t lo = hi > 0 ? hi - 1 : 0;
  if (!truth.Valid(static_cast<int>(lo), k) || !truth.Valid(static_cast<int>(hi), k)) return false;
  const double span = time[hi] - time[lo];
  const double w = span > 0 ? std::clamp((t - time[lo]) / span, 0.0, 1.0) : 0.0;
  *p = (1 - w) * truth.Position(static_cast<int>(lo), k) +
       w * truth.Position(static_cast<int>(hi), k);
  return true;
}

// The tracks' knot of each point P (index P - 1), or -1 where the tracks lack it.
std::vector<int> KnotOfPoint(const KnotTracks& tracks, int rows, int cols) {
  tracks.CheckConsistent();
  if (rows < 1 || cols < 1) throw std::invalid_argument("track export: rows, cols must be >= 1");
  std::vector<int> knot_of_point(static_cast<size_t>(rows) * cols, -1);
  for (int k = 0; k < tracks.knots(); ++k) {
    const auto [row, col] = tracks.grid[k];
    const std::string where = "track export: knot " + std::to_string(k) + " at (" +
                              std::to_string(row) + ", " + std::to_string(col) + ")";
    if (row < 0 || row >= rows || col < 0 || col >= cols)
      throw std::invalid_argument(where + " is outside the " + std::to_string(rows) + " x " +
                                  std::to_string(cols) + " net");
    int& slot = knot_of_point[row * cols + col];
    // Two knots at one grid position: the tracks hold more than one net.
    if (slot >= 0)
      throw std::invalid_argument(where + ": knot " + std::to_string(slot) + " is there too");
    slot = k;
  }
  return knot_of_point;
}

// Point number P of a header column, as matched by `pattern` (group 1); throws if P < 1.
int PointOf(const std::string& path, const std::string& column, const std::smatch& match) {
  const int p = std::stoi(match[1]);
  if (p < 1) throw InputError(path + ":1: column '" + column + "': points count from 1");
  return p;
}

}  // namespace

void WriteXyzPts(const std::string& path, const KnotTracks& tracks, int rows, int cols) {
  const std::vector<int> knot_of_point = KnotOfPoint(tracks, rows, cols);
  WriteTextFile(path, [&](std::ostream& out) {
    for (size_t p = 1; p <= knot_of_point.size(); ++p) {
      const std::string column = "pt" + std::to_string(p);
      out << (p == 1 ? "" : ",") << column << "_X," << column << "_Y," << column << "_Z";
    }
    out << '\n';
    for (int t = 0; t < tracks.frames(); ++t) {
      for (size_t i = 0; i < knot_of_point.size(); ++i) {
        const int k = knot_of_point[i];
        out << (i == 0 ? "" : ",");
        if (k >= 0 && tracks.Valid(t, k)) {
          const Eigen::Vector3d& x = tracks.Position(t, k);
          out << Number(x.x()) << ',' << Number(x.y()) << ',' << Number(x.z());
        } else {
          out << "NaN,NaN,NaN";
        }
      }
      out << '\n';
    }
  });
}

void WriteXyzRes(const std::string& path, const KnotTracks& tracks, int rows, int cols) {
  const std::vector<int> knot_of_point = KnotOfPoint(tracks, rows, cols);
  const bool known = !tracks.reprojection_error_px.empty();
  WriteTextFile(path, [&](std::ostream& out) {
    for (size_t p = 1; p <= knot_of_point.size(); ++p)
      out << (p == 1 ? "" : ",") << "pt" << p << "_dltres";
    out << '\n';
    for (int t = 0; t < tracks.frames(); ++t) {
      const size_t frame_start = static_cast<size_t>(t) * tracks.knots();
      for (size_t i = 0; i < knot_of_point.size(); ++i) {
        const int k = knot_of_point[i];
        const double residual = known && k >= 0 && tracks.Valid(t, k)
                                    ? tracks.reprojection_error_px[frame_start + k]
                                    : std::numeric_limits<double>::quiet_NaN();
        out << (i == 0 ? "" : ",") << Number(residual);
      }
      out << '\n';
    }
  });
}

std::vector<std::vector<Eigen::Vector3d>> ReadXyzPts(const std::string& path) {
  const CsvTable table = ReadCsvTable(path);
  // Point P -> its X, Y and Z columns.
  const std::regex pattern(R"(pt([0-9]{1,9})_([XYZ]))");
  std::map<int, std::array<int, 3>> points;
  for (size_t j = 0; j < table.columns.size(); ++j) {
    const std::string& column = table.columns[j];
    std::smatch match;
    if (!std::regex_match(column, match, pattern))
      throw InputError(path + ":1: column '" + column + "': expected pt{P}_X, pt{P}_Y or pt{P}_Z");
    const int p = PointOf(path, column, match);
    auto [it, inserted] = points.try_emplace(p, std::array<int, 3>{-1, -1, -1});
    int& slot = it->second[match[2].str()[0] - 'X'];
    if (slot >= 0) throw InputError(path + ":1: column '" + column + "' appears twice");
    slot = static_cast<int>(j);
  }
  for (const auto& [p, columns] : points)
    for (int axis = 0; axis < 3; ++axis)
      if (columns[axis] < 0)
        throw InputError(path + ":1: point " + std::to_string(p) + " has no column pt" +
                         std::to_string(p) + "_" + static_cast<char>('X' + axis));

  const size_t count = points.empty() ? 0 : points.rbegin()->first;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  std::vector<std::vector<Eigen::Vector3d>> positions(
      table.rows.size(), std::vector<Eigen::Vector3d>(count, Eigen::Vector3d::Constant(nan)));
  for (size_t t = 0; t < table.rows.size(); ++t)
    for (const auto& [p, columns] : points)
      positions[t][p - 1] = Eigen::Vector3d(table.rows[t][columns[0]], table.rows[t][columns[1]],
                                            table.rows[t][columns[2]]);
  return positions;
}

std::vector<std::vector<double>> ReadXyzRes(const std::string& path) {
  const CsvTable table = ReadCsvTable(path);
  const std::regex pattern(R"(pt([0-9]{1,9})_dltres)");
  std::map<int, int> column_of_point;
  for (size_t j = 0; j < table.columns.size(); ++j) {
    const std::string& column = table.columns[j];
    std::smatch match;
    if (!std::regex_match(column, match, pattern))
      throw InputError(path + ":1: column '" + column + "': expected pt{P}_dltres");
    const int p = PointOf(path, column, match);
    if (!column_of_point.emplace(p, static_cast<int>(j)).second)
      throw InputError(path + ":1: column '" + column + "' appears twice");
  }
  const size_t count = column_of_point.empty() ? 0 : column_of_point.rbegin()->first;
  std::vector<std::vector<double>> residual(
      table.rows.size(), std::vector<double>(count, std::numeric_limits<double>::quiet_NaN()));
  for (size_t t = 0; t < table.rows.size(); ++t)
    for (const auto& [p, column] : column_of_point) residual[t][p - 1] = table.rows[t][column];
  return residual;
}

KnotTracks TracksFromSequence(const SequenceResult& result, const std::vector<double>& time_s,
                              const std::string& source) {
  if (time_s.size() != result.frame_index.size())
    throw std::invalid_argument("track export: one time per frame row needed");
  KnotTracks tracks;
  tracks.source = source;
  tracks.time = time_s;
  tracks.frame_index = result.frame_index;
  for (int row = 0; row < result.rows; ++row)
    for (int col = 0; col < result.cols; ++col) tracks.grid.push_back({row, col});
  tracks.position = result.position;
  tracks.valid = result.valid;
  tracks.covariance = result.covariance;
  tracks.reprojection_error_px = result.rms_px;
  for (const auto& c : result.rig.cameras) tracks.camera_names.push_back(c.name);
  for (const auto& o : result.outliers)
    tracks.outliers.push_back({o.frame, o.knot, o.camera, o.residual_px});
  tracks.degenerate = result.degenerate;
  if (tracks.degenerate.empty() && !tracks.valid.empty())
    tracks.degenerate.assign(tracks.valid.size(), 0);
  for (const DegeneratePoint& d : result.degenerate_points)
    tracks.degenerate_points.push_back({d.frame, d.knot, d.sigma_m, d.ray_angle_deg, d.reason});
  tracks.degenerate_max_sigma_m = result.max_sigma_m;
  tracks.degenerate_bound_from = result.max_sigma_from;
  return tracks;
}

KnotTracks TracksFromSequence(const SequenceResult& result, double fps, const std::string& source) {
  std::vector<double> time;
  for (int f : result.frame_index) time.push_back(f / fps);
  return TracksFromSequence(result, time, source);
}

TruthComparison CompareWithTruth(const KnotTracks& tracks, const KnotTracks& truth) {
  // The valid points and the degenerate ones with their true positions.
  TruthComparison c;
  std::vector<Eigen::Vector3d> measured, truth_of, degenerate, truth_of_degenerate;
  std::vector<Eigen::Matrix3d> covariance;
  for (int t = 0; t < tracks.frames(); ++t)
    for (int k = 0; k < tracks.knots(); ++k) {
      const bool valid = tracks.Valid(t, k), flagged = tracks.Degenerate(t, k);
      if (!valid && !flagged) continue;
      const int tk = truth.FindKnot(tracks.grid[k][0], tracks.grid[k][1]);
      Eigen::Vector3d p;
      if (tk < 0 || !TruthAt(truth, tk, tracks.time[t], &p)) continue;
      if (valid) {
        measured.push_back(tracks.Position(t, k));
        truth_of.push_back(p);
        covariance.push_back(tracks.covariance[static_cast<size_t>(t) * tracks.knots() + k]);
      } else if (tracks.Position(t, k).allFinite()) {
        degenerate.push_back(tracks.Position(t, k));
        truth_of_degenerate.push_back(p);
      }
    }
  c.points = static_cast<int64_t>(measured.size());
  c.degenerate_points = static_cast<int64_t>(degenerate.size());
  if (c.points < 3) return c;
  // truth_from_tracks, fitted to the valid points.
  const Eigen::Map<const Eigen::Matrix3Xd> from(measured[0].data(), 3, c.points);
  const Eigen::Map<const Eigen::Matrix3Xd> to(truth_of[0].data(), 3, c.points);
  const Eigen::Matrix4d m = Eigen::umeyama(from, to, false);
  const Eigen::Matrix3d r = m.topLeftCorner<3, 3>();
  const Eigen::Vector3d shift = m.topRightCorner<3, 1>();
  c.aligned = true;
  c.rotation_deg = Eigen::AngleAxisd(r).angle() * 180.0 / M_PI;
  c.translation_m = shift.norm();
  double ss = 0.0, mahalanobis = 0.0;
  for (int64_t i = 0; i < c.points; ++i) {
    const Eigen::Vector3d e = r * measured[i] + shift - truth_of[i];
    ss += e.squaredNorm();
    c.max_m = std::max(c.max_m, e.norm());
    const Eigen::Matrix3d cov = r * covariance[i] * r.transpose();
    mahalanobis += e.dot(cov.ldlt().solve(e));
  }
  c.rms_m = std::sqrt(ss / static_cast<double>(c.points));
  c.mean_mahalanobis2 = mahalanobis / static_cast<double>(c.points);
  double dss = 0.0;
  for (size_t i = 0; i < degenerate.size(); ++i) {
    const double e = (r * degenerate[i] + shift - truth_of_degenerate[i]).norm();
    dss += e * e;
    c.degenerate_max_m = std::max(c.degenerate_max_m, e);
  }
  if (!degenerate.empty()) c.degenerate_rms_m = std::sqrt(dss / degenerate.size());
  return c;
}

}  // namespace netlab::recon
