#include "calibration/target.h"

#include <cmath>
#include <filesystem>
#include <map>
#include <sstream>
#include <stdexcept>

#include "common/yaml_util.h"

namespace netlab::calib {
namespace {

[[noreturn]] void Fail(const std::string& message) { throw std::invalid_argument(message); }

const std::map<std::string, int>& DictionaryNames() {
  using namespace cv::aruco;
  static const std::map<std::string, int> names = {
      {"DICT_4X4_50", DICT_4X4_50},
      {"DICT_4X4_100", DICT_4X4_100},
      {"DICT_4X4_250", DICT_4X4_250},
      {"DICT_4X4_1000", DICT_4X4_1000},
      {"DICT_5X5_50", DICT_5X5_50},
      {"DICT_5X5_100", DICT_5X5_100},
      {"DICT_5X5_250", DICT_5X5_250},
      {"DICT_5X5_1000", DICT_5X5_1000},
      {"DICT_6X6_50", DICT_6X6_50},
      {"DICT_6X6_100", DICT_6X6_100},
      {"DICT_6X6_250", DICT_6X6_250},
      {"DICT_6X6_1000", DICT_6X6_1000},
      {"DICT_7X7_50", DICT_7X7_50},
      {"DICT_7X7_100", DICT_7X7_100},
      {"DICT_7X7_250", DICT_7X7_250},
      {"DICT_7X7_1000", DICT_7X7_1000},
      {"DICT_ARUCO_ORIGINAL", DICT_ARUCO_ORIGINAL},
  };
  return names;
}

// "9x6" -> (9, 6).
std::pair<int, int> ParseSize(const std::string& text, const std::string& spec) {
  const size_t x = text.find('x');
  try {
    if (x == std::string::npos) throw std::invalid_argument("");
    size_t used_a = 0, used_b = 0;
    const int a = std::stoi(text.substr(0, x), &used_a);
    const int b = std::stoi(text.substr(x + 1), &used_b);
    if (used_a != x || used_b != text.size() - x - 1) throw std::invalid_argument("");
    return {a, b};
  } catch (const std::exception&) {
    Fail("board '" + spec + "': expected COLSxROWS, got '" + text + "'");
  }
}

double ParseLength(const std::string& text, const std::string& what, const std::string& spec) {
  try {
    size_t used = 0;
    const double v = std::stod(text, &used);
    if (used == text.size() && v > 0.0 && std::isfinite(v)) return v;
  } catch (const std::exception&) {
  }
  Fail("board '" + spec + "': " + what + " must be a positive length in m, got '" + text + "'");
}

std::vector<std::string> Split(const std::string& text, char sep) {
  std::vector<std::string> parts;
  std::stringstream ss(text);
  std::string part;
  while (std::getline(ss, part, sep)) parts.push_back(part);
  return parts;
}

// A pattern from a YAML mapping (the board part of a board or foil file).
BoardPattern PatternFromYaml(const YamlMap& m) {
  const std::string type = m.String("type");
  try {
    if (type == "chessboard") {
      m.AllowOnly({"type", "cols", "rows", "square"});
      return BoardPattern::Chessboard(m.Int("cols"), m.Int("rows"), m.Positive("square"));
    }
    if (type == "charuco") {
      m.AllowOnly({"type", "cols", "rows", "square", "marker", "dictionary"});
      return BoardPattern::Charuco(m.Int("cols"), m.Int("rows"), m.Positive("square"),
                                   m.Positive("marker"), m.String("dictionary"));
    }
  } catch (const std::invalid_argument& e) {
    m.Fail(m.node(), e.what());
  }
  m.Fail("type", "expected chessboard or charuco, got '" + type + "'");
}

Eigen::Vector3d ToVector(const std::array<double, 3>& a) { return {a[0], a[1], a[2]}; }

}  // namespace

cv::Ptr<cv::aruco::Dictionary> ArucoDictionary(const std::string& name) {
  const auto& names = DictionaryNames();
  const auto it = names.find(name);
  if (it == names.end()) {
    std::string known;
    for (const auto& [n, id] : names) known += (known.empty() ? "" : ", ") + n;
    Fail("unknown ArUco dictionary '" + name + "' (known: " + known + ")");
  }
  return cv::aruco::getPredefinedDictionary(it->second);
}

BoardPattern BoardPattern::Chessboard(int cols, int rows, double square) {
  if (cols < 3 || rows < 3) Fail("chessboard: need at least 3x3 inner corners");
  if ((cols + rows) % 2 == 0)
    Fail("chessboard " + std::to_string(cols) + "x" + std::to_string(rows) +
         ": inner corners must be odd by even (e.g. 9x6) so the pattern's orientation is unique");
  if (!(square > 0.0)) Fail("chessboard: square must be > 0");
  BoardPattern p;
  p.type = PatternType::kChessboard;
  p.cols = cols;
  p.rows = rows;
  p.square = square;
  for (int r = 0; r < rows; ++r)
    for (int c = 0; c < cols; ++c) {
      p.points.emplace_back(c * square, r * square, 0.0);
      if (c + 1 < cols) p.neighbours.emplace_back(r * cols + c, r * cols + c + 1);
      if (r + 1 < rows) p.neighbours.emplace_back(r * cols + c, (r + 1) * cols + c);
    }
  p.extent_min = Eigen::Vector2d(-square, -square);
  p.extent_max = Eigen::Vector2d(cols * square, rows * square);
  return p;
}

BoardPattern BoardPattern::Charuco(int cols, int rows, double square, double marker,
                                   const std::string& dictionary) {
  if (cols < 3 || rows < 3) Fail("charuco: need at least 3x3 squares");
  if (!(square > 0.0) || !(marker > 0.0) || !(marker < square))
    Fail("charuco: need 0 < marker < square");
  BoardPattern p;
  p.type = PatternType::kCharuco;
  p.cols = cols;
  p.rows = rows;
  p.square = square;
  p.marker = marker;
  p.dictionary = dictionary;
  p.aruco_dictionary = ArucoDictionary(dictionary);
  const int markers_needed = (cols * rows) / 2;
  if (p.aruco_dictionary->bytesList.rows < markers_needed)
    Fail("charuco " + std::to_string(cols) + "x" + std::to_string(rows) + ": needs " +
         std::to_string(markers_needed) + " markers, " + dictionary + " has " +
         std::to_string(p.aruco_dictionary->bytesList.rows));
  p.charuco = cv::aruco::CharucoBoard::create(cols, rows, static_cast<float>(square),
                                              static_cast<float>(marker), p.aruco_dictionary);
  const int inner_cols = cols - 1;
  for (size_t i = 0; i < p.charuco->chessboardCorners.size(); ++i) {
    const cv::Point3f& c = p.charuco->chessboardCorners[i];
    p.points.emplace_back(c.x, c.y, c.z);
    const int id = static_cast<int>(i);
    if ((id % inner_cols) + 1 < inner_cols) p.neighbours.emplace_back(id, id + 1);
    if (id + inner_cols < static_cast<int>(p.charuco->chessboardCorners.size()))
      p.neighbours.emplace_back(id, id + inner_cols);
  }
  p.extent_min = Eigen::Vector2d(0.0, 0.0);
  p.extent_max = Eigen::Vector2d(cols * square, rows * square);
  // Handedness of the print from the first marker's corners (top-left, top-right, ...,
  // bottom-left as seen): y "down" as seen puts the viewer at -z.
  const auto& m = p.charuco->objPoints.at(0);
  const cv::Point3f right = m[1] - m[0], down = m[3] - m[0];
  p.viewer_z = right.x * down.y - right.y * down.x > 0.0f ? -1.0 : 1.0;
  return p;
}

CalibrationTarget CalibrationTarget::Board(BoardPattern pattern) {
  CalibrationTarget t;
  t.kind = Kind::kBoard;
  t.faces.push_back({"board", std::move(pattern), Rigid3d()});
  t.description = "board";
  return t;
}

CalibrationTarget CalibrationTarget::Foil(BoardPattern pattern, double thickness, char flip_axis,
                                          const Eigen::Vector2d& back_offset) {
  if (!(thickness >= 0.0)) Fail("foil: thickness must be >= 0");
  if (flip_axis != 'x' && flip_axis != 'y') Fail("foil: flip_axis must be x or y");
  // The back print is the front print turned about one board axis (a proper rotation,
  // diag(-1, 1, -1) for y), mirrored about the print's centre line and lying `thickness` behind the
  // front surface, on the side away from the front's viewer.
  const Eigen::Vector2d sum = pattern.extent_min + pattern.extent_max;
  Eigen::Matrix3d r;
  Eigen::Vector3d t;
  if (flip_axis == 'y') {
    r = Eigen::Vector3d(-1, 1, -1).asDiagonal();
    t = Eigen::Vector3d(sum.x(), 0.0, -pattern.viewer_z * thickness);
  } else {
    r = Eigen::Vector3d(1, -1, -1).asDiagonal();
    t = Eigen::Vector3d(0.0, sum.y(), -pattern.viewer_z * thickness);
  }
  t.head<2>() += back_offset;
  CalibrationTarget target;
  target.kind = Kind::kDoubleSidedFoil;
  target.thickness = thickness;
  target.faces.push_back({"front", pattern, Rigid3d()});
  target.faces.push_back({"back", std::move(pattern), Rigid3d(r, t)});
  target.description = "double-sided foil";
  return target;
}

CalibrationTarget CalibrationTarget::MarkerMap(
    const std::string& dictionary,
    const std::vector<std::pair<int, std::array<Eigen::Vector3d, 4>>>& markers) {
  BoardPattern p;
  p.type = PatternType::kMarkers;
  p.dictionary = dictionary;
  p.aruco_dictionary = ArucoDictionary(dictionary);
  int max_id = -1;
  for (const auto& [id, corners] : markers) {
    if (id < 0 || id >= p.aruco_dictionary->bytesList.rows)
      Fail("marker map: id " + std::to_string(id) + " is not in " + dictionary);
    max_id = std::max(max_id, id);
  }
  p.points.assign(4 * (max_id + 1), Eigen::Vector3d::Constant(std::nan("")));
  for (const auto& [id, corners] : markers) {
    if (p.points[4 * id].allFinite()) Fail("marker map: marker " + std::to_string(id) + " twice");
    for (int k = 0; k < 4; ++k) p.points[4 * id + k] = corners[k];
    for (int k = 0; k < 4; ++k) p.neighbours.emplace_back(4 * id + k, 4 * id + (k + 1) % 4);
  }
  if (markers.empty()) Fail("marker map: no markers");
  CalibrationTarget target;
  target.kind = Kind::kMarkerMap;
  target.faces.push_back({"markers", std::move(p), Rigid3d()});
  target.description = "marker map";
  return target;
}

std::array<Eigen::Vector3d, 4> MarkerCorners(const Eigen::Vector3d& center,
                                             const Eigen::Vector3d& x_axis,
                                             const Eigen::Vector3d& normal, double size) {
  // Marker frame as a face: z into the print (against the normal), x as given, y = z cross x
  // (down as seen from the front).
  const Eigen::Vector3d z = -normal.normalized();
  const Eigen::Vector3d x = (x_axis - x_axis.dot(z) * z).normalized();
  const Eigen::Vector3d y = z.cross(x);
  const double h = 0.5 * size;
  return {center - h * x - h * y, center + h * x - h * y, center + h * x + h * y,
          center - h * x + h * y};
}

CalibrationTarget CalibrationTarget::Parse(const std::string& spec) {
  const std::vector<std::string> parts = Split(spec, ':');
  if (!parts.empty() && parts[0] == "chessboard") {
    if (parts.size() != 3) Fail("board '" + spec + "': expected chessboard:COLSxROWS:SQUARE");
    const auto [cols, rows] = ParseSize(parts[1], spec);
    return Board(BoardPattern::Chessboard(cols, rows, ParseLength(parts[2], "SQUARE", spec)));
  }
  if (!parts.empty() && parts[0] == "charuco") {
    if (parts.size() != 5)
      Fail("board '" + spec + "': expected charuco:COLSxROWS:SQUARE:MARKER:DICT");
    const auto [cols, rows] = ParseSize(parts[1], spec);
    return Board(BoardPattern::Charuco(cols, rows, ParseLength(parts[2], "SQUARE", spec),
                                       ParseLength(parts[3], "MARKER", spec), parts[4]));
  }
  if (!std::filesystem::exists(spec))
    Fail("board '" + spec + "': not chessboard:..., charuco:... nor an existing YAML file");

  // A YAML file: a board, a double-sided foil or a marker map.
  const YamlMap root(LoadYamlFile(spec), spec, "");
  const std::string type = root.String("type");
  if (type == "chessboard" || type == "charuco") return Board(PatternFromYaml(root));
  if (type == "double_sided_foil") {
    root.AllowOnly({"type", "board", "thickness", "flip_axis", "back_offset", "back_cameras"});
    const BoardPattern pattern = PatternFromYaml(root.Map("board"));
    const std::string axis = root.String("flip_axis", "y");
    if (axis != "x" && axis != "y") root.Fail("flip_axis", "expected x or y");
    Eigen::Vector2d offset = Eigen::Vector2d::Zero();
    if (root.Has("back_offset")) {
      const std::vector<double> o = root.Doubles("back_offset");
      if (o.size() != 2) root.Fail("back_offset", "expected [dx, dy] in m");
      offset = Eigen::Vector2d(o[0], o[1]);
    }
    CalibrationTarget target = Foil(pattern, root.Positive("thickness", true), axis[0], offset);
    if (root.Has("back_cameras")) {
      const YAML::Node list = root.Get("back_cameras");
      if (!list.IsSequence()) root.Fail("back_cameras", "expected a list of camera names");
      for (const auto& n : list) target.back_cameras.push_back(n.as<std::string>());
    }
    return target;
  }
  if (type == "marker_map") {
    root.AllowOnly({"type", "dictionary", "markers"});
    const std::string dictionary = root.String("dictionary");
    try {
      ArucoDictionary(dictionary);
    } catch (const std::invalid_argument& e) {
      root.Fail("dictionary", e.what());
    }
    const YAML::Node list = root.Get("markers");
    if (!list.IsSequence()) root.Fail("markers", "expected a list of markers");
    std::vector<std::pair<int, std::array<Eigen::Vector3d, 4>>> markers;
    for (size_t i = 0; i < list.size(); ++i) {
      const YamlMap m(list[i], spec, "markers[" + std::to_string(i) + "]");
      m.AllowOnly({"id", "corners", "center", "x_axis", "normal", "size"});
      std::array<Eigen::Vector3d, 4> corners;
      if (m.Has("corners")) {
        const YAML::Node c = m.Get("corners");
        if (!c.IsSequence() || c.size() != 4) m.Fail("corners", "expected 4 corners [x, y, z]");
        for (int k = 0; k < 4; ++k) {
          YAML::Node holder;
          holder["c"] = c[k];
          corners[k] = ToVector(YamlMap(holder, spec, m.Join("corners")).Vec3("c"));
        }
      } else {
        corners = MarkerCorners(ToVector(m.Vec3("center")), ToVector(m.Vec3("x_axis")),
                                ToVector(m.Vec3("normal")), m.Positive("size"));
      }
      markers.emplace_back(m.Int("id"), corners);
    }
    try {
      return MarkerMap(dictionary, markers);
    } catch (const std::invalid_argument& e) {
      root.Fail("markers", e.what());
    }
  }
  root.Fail("type",
            "expected chessboard, charuco, double_sided_foil or marker_map, got '" + type + "'");
}

}  // namespace netlab::calib
