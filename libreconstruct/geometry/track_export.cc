#include "libreconstruct/geometry/track_export.h"

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

#include "common/yaml_util.h"
#include "libreconstruct/labels/csv_table.h"

namespace netlab::recon {
namespace {

// The tracks' knot of each point P (index P - 1), or -1 where the tracks lack it.
std::vector<int> KnotOfPoint(const netsim::KnotTracks& tracks, int rows, int cols) {
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

void WriteXyzPts(const std::string& path, const netsim::KnotTracks& tracks, int rows, int cols) {
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

void WriteXyzRes(const std::string& path, const netsim::KnotTracks& tracks, int rows, int cols) {
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

}  // namespace netlab::recon
