#include "libreconstruct/labels/label_set.h"

#include <algorithm>
#include <array>
#include <cctype>
#include <charconv>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <mutex>
#include <optional>
#include <regex>
#include <set>
#include <sstream>
#include <stdexcept>
#include <utility>

#include "common/errors.h"
#include "common/files.h"
#include "common/hdf5_util.h"
#include "common/memory.h"
#include "libreconstruct/labels/csv_table.h"

namespace netlab::recon {
namespace {

constexpr char kLabelsFormat[] = "netlab-labels";
constexpr int kLastSource = static_cast<int>(LabelSource::kProjected);
constexpr int kLastState = static_cast<int>(LabelState::kHidden);

std::string Shape(const std::vector<hsize_t>& dims) {
  std::string shape;
  for (hsize_t d : dims) {
    if (!shape.empty()) shape += ',';
    shape += std::to_string(d);
  }
  return "[" + shape + "]";
}

// Sizes and value ranges: a set that breaks them is a programming error, and writing it would
// give a file that ReadLabels refuses.
void CheckConsistent(const LabelSet& labels) {
  auto fail = [](const std::string& what) { throw std::invalid_argument("label set: " + what); };
  if (labels.rows < 1 || labels.cols < 1) fail("rows and cols must be >= 1");
  if (labels.labels.size() != labels.cameras.size()) fail("labels must hold one entry per camera");
  const size_t cells = static_cast<size_t>(labels.frames()) * labels.knots();
  for (size_t c = 0; c < labels.labels.size(); ++c) {
    if (labels.labels[c].size() != cells)
      fail("camera '" + labels.cameras[c] + "' must hold frames x knots labels");
    for (size_t i = 0; i < cells; ++i) {
      const Label& label = labels.labels[c][i];
      if (static_cast<int>(label.source) > kLastSource ||
          static_cast<int>(label.state) > kLastState ||
          !(label.confidence >= 0.0f && label.confidence <= 1.0f))
        fail("camera '" + labels.cameras[c] + "', row " + std::to_string(i / labels.knots()) +
             ", knot " + std::to_string(i % labels.knots()) +
             ": source, state or confidence out of range");
      if (label.hidden() && !(std::isnan(label.px.x()) && std::isnan(label.px.y())))
        fail("camera '" + labels.cameras[c] + "', row " + std::to_string(i / labels.knots()) +
             ", knot " + std::to_string(i % labels.knots()) + ": a hidden mark has a position");
    }
  }
}

// ---------------------------------------------------------------------------------------------
// labels.h5

void WriteIntAttribute(hid_t obj, const std::string& path, const std::string& name, int value) {
  h5::Id space(H5Screate(H5S_SCALAR));
  h5::Id attr(H5Acreate2(obj, name.c_str(), H5T_NATIVE_INT, space.get(), H5P_DEFAULT, H5P_DEFAULT));
  if (!attr.valid() || H5Awrite(attr.get(), H5T_NATIVE_INT, &value) < 0)
    throw std::runtime_error(path + ": cannot write attribute " + name);
}

std::optional<int> ReadIntAttribute(hid_t obj, const std::string& name) {
  if (H5Aexists(obj, name.c_str()) <= 0) return std::nullopt;
  h5::Id attr(H5Aopen(obj, name.c_str(), H5P_DEFAULT));
  h5::Id type(H5Aget_type(attr.get()));
  h5::Id space(H5Aget_space(attr.get()));
  int value = 0;
  if (H5Tget_class(type.get()) != H5T_INTEGER || H5Sget_simple_extent_npoints(space.get()) != 1 ||
      H5Aread(attr.get(), H5T_NATIVE_INT, &value) < 0)
    return std::nullopt;
  return value;
}

// Names of the links in `group`, in HDF5's name order.
std::vector<std::string> GroupMembers(hid_t group) {
  H5G_info_t info;
  if (H5Gget_info(group, &info) < 0) return {};
  std::vector<std::string> names;
  for (hsize_t i = 0; i < info.nlinks; ++i) {
    const ssize_t size =
        H5Lget_name_by_idx(group, ".", H5_INDEX_NAME, H5_ITER_INC, i, nullptr, 0, H5P_DEFAULT);
    if (size < 0) continue;
    std::vector<char> name(size + 1, '\0');
    H5Lget_name_by_idx(group, ".", H5_INDEX_NAME, H5_ITER_INC, i, name.data(), name.size(),
                       H5P_DEFAULT);
    names.emplace_back(name.data(), size);
  }
  return names;
}

void WriteCamera(hid_t cameras, const LabelSet& labels, int c) {
  const std::string& name = labels.cameras[c];
  const size_t cells = labels.labels[c].size();
  std::vector<double> position(2 * cells);
  std::vector<uint8_t> source(cells), state(cells);
  std::vector<float> confidence(cells);
  for (size_t i = 0; i < cells; ++i) {
    const Label& label = labels.labels[c][i];
    position[2 * i] = label.px.x();
    position[2 * i + 1] = label.px.y();
    source[i] = static_cast<uint8_t>(label.source);
    state[i] = static_cast<uint8_t>(label.state);
    confidence[i] = label.confidence;
  }
  const hsize_t t = labels.frames(), k = labels.knots();
  h5::Id group = h5::CreateGroup(cameras, name);
  const hid_t g = group.get();
  // Mostly NaN and repeated enums: deflate shrinks them many times.
  h5::WriteDataset(g, "position_px", H5T_NATIVE_DOUBLE, {t, k, 2}, position.data(), 4);
  h5::SetUnits(g, "position_px", "px");
  h5::WriteDataset(g, "source", H5T_NATIVE_UINT8, {t, k}, source.data(), 4);
  h5::SetUnits(g, "source", "1");
  h5::WriteDataset(g, "confidence", H5T_NATIVE_FLOAT, {t, k}, confidence.data(), 4);
  h5::SetUnits(g, "confidence", "1");
  h5::WriteDataset(g, "state", H5T_NATIVE_UINT8, {t, k}, state.data(), 4);
  h5::SetUnits(g, "state", "1");
}

void WriteLabelsFile(const std::string& file_path, const LabelSet& labels) {
  std::lock_guard<std::mutex> lock(h5::Mutex());
  h5::Id file = h5::CreateFile(file_path);
  const hid_t f = file.get();
  h5::WriteStringAttribute(f, "format", kLabelsFormat);
  h5::WriteStringAttribute(f, "version", "1");
  WriteIntAttribute(f, file_path, "rows", labels.rows);
  WriteIntAttribute(f, file_path, "cols", labels.cols);
  h5::WriteStringAttribute(f, "cameras", h5::JoinLines(labels.cameras));
  const hsize_t t = labels.frames(), k = labels.knots();
  h5::WriteDataset(f, "frame_index", H5T_NATIVE_INT, {t}, labels.frame_index.data());
  h5::SetUnits(f, "frame_index", "index");
  std::vector<int> grid;
  for (int r = 0; r < labels.rows; ++r)
    for (int c = 0; c < labels.cols; ++c) grid.insert(grid.end(), {r, c});
  h5::Id knots = h5::CreateGroup(f, "knots");
  h5::WriteDataset(knots.get(), "grid", H5T_NATIVE_INT, {k, 2}, grid.data());
  h5::SetUnits(knots.get(), "grid", "(row, col)");
  h5::Id cameras = h5::CreateGroup(f, "cameras");
  for (int c = 0; c < static_cast<int>(labels.cameras.size()); ++c)
    WriteCamera(cameras.get(), labels, c);
  if (!labels.reasons.empty()) {
    std::string text;
    for (const auto& [key, why] : labels.reasons) {
      std::string line = why;  // one line each: no tab or line break inside
      for (char& ch : line)
        if (ch == '\t' || ch == '\n' || ch == '\r') ch = ' ';
      text += std::to_string(key.camera) + "\t" + std::to_string(key.t) + "\t" +
              std::to_string(key.knot) + "\t" + line + "\n";
    }
    h5::WriteStringDataset(f, "review_reasons", text);
  }
  if (H5Fflush(f, H5F_SCOPE_GLOBAL) < 0)
    throw std::runtime_error(file_path + ": cannot flush (is the disk full?)");
}

// /review_reasons: "camera<TAB>t<TAB>knot<TAB>reason" lines, each address inside the set.
ReviewReasons ReadReasons(const std::string& path, hid_t f, const LabelSet& labels) {
  ReviewReasons reasons;
  std::istringstream text(h5::ReadStringDataset(f, "review_reasons"));
  int line_no = 0;
  for (std::string line; std::getline(text, line);) {
    ++line_no;
    if (line.empty()) continue;
    std::istringstream fields(line);
    int c = -1, t = -1, k = -1;
    std::string why;
    if (!(fields >> c >> t >> k) || c < 0 || c >= static_cast<int>(labels.cameras.size()) ||
        t < 0 || t >= labels.frames() || k < 0 || k >= labels.knots())
      throw InputError(path + ": /review_reasons line " + std::to_string(line_no) +
                       ": not 'camera frame-row knot reason' inside the set: " + line);
    fields.ignore(1);  // the tab before the reason
    std::getline(fields, why);
    reasons[{c, t, k}] = why;
  }
  return reasons;
}

// Reads an open labels file; HDF5 failures surface as std::runtime_error.
LabelSet ReadLabelsFile(const std::string& path, hid_t f) {
  auto fail = [&](const std::string& what) { throw InputError(path + ": " + what); };
  const std::string format = h5::ReadStringAttribute(f, "format");
  if (format != kLabelsFormat)
    fail("not a labels file (root attribute format is '" + format + "', expected '" +
         kLabelsFormat + "')");
  const std::string version = h5::ReadStringAttribute(f, "version");
  if (version != "1") fail("labels file version '" + version + "' is not supported (expected 1)");

  LabelSet labels;
  for (auto [name, value] : {std::pair("rows", &labels.rows), std::pair("cols", &labels.cols)}) {
    const std::optional<int> read = ReadIntAttribute(f, name);
    if (!read) fail(std::string("root attribute ") + name + " is missing or not an integer");
    if (*read < 1)
      fail(std::string("root attribute ") + name + " must be >= 1, got " + std::to_string(*read));
    *value = *read;
  }
  if (int64_t{labels.rows} * labels.cols > std::numeric_limits<int>::max())
    fail("rows x cols (" + std::to_string(labels.rows) + " x " + std::to_string(labels.cols) +
         ") is too large");
  if (H5Aexists(f, "cameras") <= 0) fail("root attribute cameras is missing");
  labels.cameras = h5::SplitLines(h5::ReadStringAttribute(f, "cameras"));

  // Every dataset present with the shape that /frame_index and the net's size give.
  auto expect = [&](const std::string& name, const std::vector<hsize_t>& dims) {
    if (!h5::Exists(f, name))
      fail("missing dataset " + name + " (expected shape " + Shape(dims) + ")");
    const std::vector<hsize_t> got = h5::DatasetDims(f, name);
    if (got != dims) fail(name + " has shape " + Shape(got) + ", expected " + Shape(dims));
  };
  if (!h5::Exists(f, "/frame_index")) fail("missing dataset /frame_index (expected shape [T])");
  const std::vector<hsize_t> frame_dims = h5::DatasetDims(f, "/frame_index");
  if (frame_dims.size() != 1)
    fail("/frame_index has shape " + Shape(frame_dims) + ", expected [T]");
  const hsize_t t = frame_dims[0], k = static_cast<hsize_t>(labels.knots());
  // A dataset's extent costs nothing to declare: sized before anything is allocated (it ended in
  // a bare "out of memory" naming neither the file nor the frames).
  if (const std::string shortfall = MemoryShortfall(
          static_cast<double>(t) * static_cast<double>(k) *
          static_cast<double>(std::max<size_t>(1, labels.cameras.size())) * sizeof(Label));
      !shortfall.empty())
    fail("/frame_index gives " + std::to_string(t) + " frames of " + std::to_string(k) +
         " knots in " + std::to_string(labels.cameras.size()) + " cameras: reading them " +
         shortfall);
  labels.frame_index.resize(t);
  h5::ReadDataset(f, "/frame_index", H5T_NATIVE_INT, labels.frame_index.data());
  // Repeated or backward frames gave a /time that stood still or ran back downstream.
  for (hsize_t i = 0; i < t; ++i)
    if (labels.frame_index[i] < 0 || (i > 0 && labels.frame_index[i] <= labels.frame_index[i - 1]))
      fail("/frame_index[" + std::to_string(i) + "] = " + std::to_string(labels.frame_index[i]) +
           (labels.frame_index[i] < 0 ? " is negative"
                                      : " is not after [" + std::to_string(i - 1) +
                                            "] = " + std::to_string(labels.frame_index[i - 1])));

  expect("/knots/grid", {k, 2});
  std::vector<int> grid(2 * k);
  h5::ReadDataset(f, "/knots/grid", H5T_NATIVE_INT, grid.data());
  for (hsize_t i = 0; i < k; ++i) {
    const int row = static_cast<int>(i) / labels.cols, col = static_cast<int>(i) % labels.cols;
    if (grid[2 * i] != row || grid[2 * i + 1] != col)
      fail("/knots/grid: knot " + std::to_string(i) + " is (" + std::to_string(grid[2 * i]) + ", " +
           std::to_string(grid[2 * i + 1]) + "), expected (" + std::to_string(row) + ", " +
           std::to_string(col) + ") (row-major order)");
  }

  // The cameras attribute gives the order; the groups under /cameras must be exactly those.
  if (!h5::Exists(f, "/cameras")) fail("missing group /cameras");
  h5::Id group(H5Gopen2(f, "/cameras", H5P_DEFAULT));
  if (!group.valid()) fail("/cameras is not a group");
  const std::vector<std::string> members = GroupMembers(group.get());
  const std::set<std::string> listed(labels.cameras.begin(), labels.cameras.end());
  if (listed.size() != labels.cameras.size()) fail("root attribute cameras names a camera twice");
  for (const std::string& member : members)
    if (!listed.count(member))
      fail("/cameras/" + member + " is not listed in the root attribute cameras");
  for (const std::string& name : labels.cameras)
    if (std::find(members.begin(), members.end(), name) == members.end())
      fail("camera '" + name + "' of the root attribute cameras has no group /cameras/" + name);

  const size_t cells = t * k;
  for (const std::string& name : labels.cameras) {
    const std::string prefix = "/cameras/" + name + "/";
    for (const char* dataset : {"source", "confidence", "state"}) expect(prefix + dataset, {t, k});
    expect(prefix + "position_px", {t, k, 2});
    h5::UnitsFactor(f, path, prefix + "position_px", h5::kPixels);  // px, or refused
    std::vector<double> position(2 * cells);
    std::vector<uint8_t> source(cells), state(cells);
    std::vector<float> confidence(cells);
    h5::ReadDataset(f, prefix + "position_px", H5T_NATIVE_DOUBLE, position.data());
    h5::ReadDataset(f, prefix + "source", H5T_NATIVE_UINT8, source.data());
    h5::ReadDataset(f, prefix + "confidence", H5T_NATIVE_FLOAT, confidence.data());
    h5::ReadDataset(f, prefix + "state", H5T_NATIVE_UINT8, state.data());
    auto where = [&](size_t i) {
      return " at row " + std::to_string(i / k) + ", knot " + std::to_string(i % k);
    };
    std::vector<Label>& camera = labels.labels.emplace_back(cells);
    for (size_t i = 0; i < cells; ++i) {
      if (source[i] > kLastSource)
        fail(prefix + "source: " + std::to_string(source[i]) + where(i) +
             " is not a LabelSource (0.." + std::to_string(kLastSource) + ")");
      if (state[i] > kLastState)
        fail(prefix + "state: " + std::to_string(state[i]) + where(i) +
             " is not a LabelState (0.." + std::to_string(kLastState) + ")");
      if (!(confidence[i] >= 0.0f && confidence[i] <= 1.0f))
        fail(prefix + "confidence: " + Number(confidence[i]) + where(i) + " is outside 0..1");
      // A hidden mark says the knot is not seen: a position with it contradicts it.
      if (state[i] == static_cast<uint8_t>(LabelState::kHidden) &&
          !(std::isnan(position[2 * i]) && std::isnan(position[2 * i + 1])))
        fail(prefix + "state: 3 (hidden)" + where(i) + " has a position in " + prefix +
             "position_px (a hidden mark has none: NaN)");
      // A label that says where the knot is must give a position: one at (inf, 1e300) was read
      // as no label and dropped without a word, an all-NaN file triangulated nothing with exit 0.
      const bool finite = std::isfinite(position[2 * i]) && std::isfinite(position[2 * i + 1]);
      const bool empty = std::isnan(position[2 * i]) && std::isnan(position[2 * i + 1]);
      if (!finite && (!empty || (state[i] != static_cast<uint8_t>(LabelState::kHidden) &&
                                 (source[i] != 0 || state[i] != 0))))
        fail(prefix + "position_px: (" + Number(position[2 * i]) + ", " +
             Number(position[2 * i + 1]) + ")" + where(i) +
             " is not a position (a label's is finite; NaN, NaN only where there is no label)");
      camera[i].px = Eigen::Vector2d(position[2 * i], position[2 * i + 1]);
      camera[i].source = static_cast<LabelSource>(source[i]);
      camera[i].confidence = confidence[i];
      camera[i].state = static_cast<LabelState>(state[i]);
    }
  }
  if (h5::Exists(f, "review_reasons")) labels.reasons = ReadReasons(path, f, labels);
  return labels;
}

}  // namespace

LabelSet LabelSet::Empty(int rows, int cols, const std::vector<std::string>& cameras,
                         const std::vector<int>& frame_index) {
  LabelSet set;
  set.rows = rows;
  set.cols = cols;
  set.cameras = cameras;
  set.frame_index = frame_index;
  set.labels.assign(cameras.size(),
                    std::vector<Label>(static_cast<size_t>(set.frames()) * set.knots()));
  return set;
}

int LabelSet::FindCamera(const std::string& name) const {
  const auto it = std::find(cameras.begin(), cameras.end(), name);
  return it == cameras.end() ? -1 : static_cast<int>(it - cameras.begin());
}

int64_t LabelSet::CountPresent() const {
  int64_t count = 0;
  for (const std::vector<Label>& camera : labels)
    for (const Label& label : camera) count += label.present();
  return count;
}

void WriteLabels(const std::string& path, const LabelSet& labels) {
  CheckConsistent(labels);
  for (const std::string& name : labels.cameras)
    if (name.empty() || name == "." || name.find_first_of("/\n") != std::string::npos)
      throw std::invalid_argument("label set: camera name '" + name +
                                  "' cannot name an HDF5 group");
  if (std::set<std::string>(labels.cameras.begin(), labels.cameras.end()).size() !=
      labels.cameras.size())
    throw std::invalid_argument("label set: a camera is named twice");
  const std::string partial = path + ".partial";
  try {
    WriteLabelsFile(partial, labels);
  } catch (...) {
    std::error_code ignored;
    std::filesystem::remove(partial, ignored);
    throw;
  }
  RenameInto(partial, path);
}

LabelSet ReadLabels(const std::string& path) {
  std::lock_guard<std::mutex> lock(h5::Mutex());
  try {
    h5::Id file = h5::OpenFileReadOnly(path);
    return ReadLabelsFile(path, file.get());
  } catch (const InputError&) {
    throw;
  } catch (const std::runtime_error& e) {  // unreadable or corrupt HDF5; the message names it
    throw InputError(e.what());
  }
}

void WriteXyPts(const std::string& path, const LabelSet& labels) {
  CheckConsistent(labels);
  if (labels.cameras.empty()) throw std::invalid_argument("label set: xypts.csv needs a camera");
  // Row i of the file is frame i: each row of the set goes to its frame's row, the frames
  // between them are NaN rows.
  std::vector<int> row_of_frame;
  for (int t = 0; t < labels.frames(); ++t) {
    const int frame = labels.frame_index[t];
    if (frame < 0)
      throw std::invalid_argument("label set: frame " + std::to_string(frame) +
                                  " is negative (xypts.csv rows are frames from 0)");
    if (frame >= static_cast<int>(row_of_frame.size())) row_of_frame.resize(frame + 1, -1);
    if (row_of_frame[frame] >= 0)
      throw std::invalid_argument("label set: frame " + std::to_string(frame) + " listed twice");
    row_of_frame[frame] = t;
  }
  const int points = labels.knots(), cameras = static_cast<int>(labels.cameras.size());
  WriteTextFile(path, [&](std::ostream& out) {
    for (int p = 1; p <= points; ++p)
      for (int c = 1; c <= cameras; ++c) {
        const std::string column = "pt" + std::to_string(p) + "_cam" + std::to_string(c);
        out << (p == 1 && c == 1 ? "" : ",") << column << "_X," << column << "_Y";
      }
    out << '\n';
    for (const int t : row_of_frame) {
      for (int k = 0; k < points; ++k)
        for (int c = 0; c < cameras; ++c) {
          const Label* label = t >= 0 ? &labels.at(c, t, k) : nullptr;
          out << (k == 0 && c == 0 ? "" : ",");
          if (label && label->present())
            out << Number(label->px.x()) << ',' << Number(label->px.y());
          else
            out << "NaN,NaN";
        }
      out << '\n';
    }
  });
}

LabelSet ReadXyPts(const std::string& path, int rows, int cols,
                   const std::vector<std::string>& camera_names) {
  if (rows < 1 || cols < 1) throw std::invalid_argument("ReadXyPts: rows and cols must be >= 1");
  const CsvTable table = ReadCsvTable(path);
  const int points = rows * cols, cameras = static_cast<int>(camera_names.size());

  // Header: (point, camera) -> the X and Y columns.
  const std::regex pattern(R"(pt([0-9]{1,9})_cam([0-9]{1,9})_([XY]))");
  std::map<std::pair<int, int>, std::array<int, 2>> pairs;
  for (size_t j = 0; j < table.columns.size(); ++j) {
    const std::string& column = table.columns[j];
    const std::string where = path + ":1: column '" + column + "': ";
    std::smatch match;
    if (!std::regex_match(column, match, pattern))
      throw InputError(where + "expected pt{P}_cam{C}_X or pt{P}_cam{C}_Y");
    const int p = std::stoi(match[1]), c = std::stoi(match[2]);
    if (p < 1 || p > points)
      throw InputError(where + "point " + std::to_string(p) + " is not in the " +
                       std::to_string(rows) + " x " + std::to_string(cols) + " net (points 1.." +
                       std::to_string(points) + ")");
    if (c < 1 || c > cameras)
      throw InputError(where + "camera " + std::to_string(c) + " is not one of the " +
                       std::to_string(cameras) + " cameras given (1.." + std::to_string(cameras) +
                       ")");
    auto [it, inserted] = pairs.try_emplace({p - 1, c - 1}, std::array<int, 2>{-1, -1});
    int& slot = it->second[match[3] == "X" ? 0 : 1];
    if (slot >= 0) throw InputError(where + "appears twice");
    slot = static_cast<int>(j);
  }
  for (const auto& [key, columns] : pairs)
    if (columns[0] < 0 || columns[1] < 0) {
      const std::string stem =
          "pt" + std::to_string(key.first + 1) + "_cam" + std::to_string(key.second + 1);
      throw InputError(path + ":1: column '" + stem + (columns[0] < 0 ? "_Y" : "_X") +
                       "' has no matching '" + stem + (columns[0] < 0 ? "_X" : "_Y") + "'");
    }

  std::vector<int> frame_index(table.rows.size());
  for (size_t t = 0; t < frame_index.size(); ++t) frame_index[t] = static_cast<int>(t);
  LabelSet labels = LabelSet::Empty(rows, cols, camera_names, frame_index);
  for (size_t t = 0; t < table.rows.size(); ++t)
    for (const auto& [key, columns] : pairs) {
      const double x = table.rows[t][columns[0]], y = table.rows[t][columns[1]];
      if (std::isnan(x) && std::isnan(y)) continue;
      if (std::isnan(x) || std::isnan(y))
        throw InputError(path + ":" + std::to_string(t + 2) + ": columns " +
                         table.columns[columns[0]] + " and " + table.columns[columns[1]] +
                         ": one is NaN and the other is not");
      Label& label = labels.at(key.second, static_cast<int>(t), key.first);
      label.px = Eigen::Vector2d(x, y);
      label.source = LabelSource::kImported;
      label.confidence = 1.0f;
      label.state = LabelState::kAccepted;
    }
  return labels;
}

LabelSet ReadLabelsAny(const std::string& path, int rows, int cols,
                       const std::vector<std::string>& camera_names) {
  std::string extension = std::filesystem::path(path).extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(),
                 [](unsigned char ch) { return std::tolower(ch); });
  if (extension == ".csv") return ReadXyPts(path, rows, cols, camera_names);
  LabelSet labels = ReadLabels(path);
  if (labels.rows != rows || labels.cols != cols)
    throw InputError(path + ": the labels are for a " + std::to_string(labels.rows) + " x " +
                     std::to_string(labels.cols) + " net, but the net is " + std::to_string(rows) +
                     " x " + std::to_string(cols));
  return labels;
}

}  // namespace netlab::recon
