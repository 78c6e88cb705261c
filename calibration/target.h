#pragma once
// Calibration targets: the known 3D points a camera can detect and identify.
//
// Face frames. A printed planar pattern has its own frame: origin at its first point, x along
// increasing column, y along increasing row, z = x cross y (BoardPattern::viewer_z says on which
// side the viewer stands). Points carry ids:
//   chessboard  inner corner (col, row) has id row * cols + col, at (col s, row s, 0); the square
//               diagonally outside corner 0 is black, and cols x rows must be odd x even so the
//               pattern's orientation is unique (the far corner square is then white);
//   charuco     OpenCV's ChArUco corner ids and positions (cols x rows squares);
//   markers     marker k's corners have ids 4k..4k+3 (OpenCV's order: top-left, top-right,
//               bottom-right, bottom-left as printed).
//
// A target is rigid and has one or more faces at known target_from_face transforms:
//   board        one face; target frame = face frame.
//   foil         a double-sided foil printed identically on both sides (paper sec. 5.3): the front
//                face, and the back face = the front print turned about a board axis (y by
//                default) and moved through the foil's thickness, so one pair of cameras sees the
//                front, the facing pair the back, and both land in one frame.
//   marker map   ArUco markers with known 3D corner positions (the rig, target and ejector
//                markers of sec. 5.3); target frame = the map's frame (e.g. the aircraft's).
//
// Specs: "chessboard:COLSxROWS:SQUARE" (inner corners, m), "charuco:COLSxROWS:SQUARE:MARKER:DICT"
// (squares, m, e.g. DICT_5X5_100), or the path of a YAML file (docs/calibration.md).

#include <opencv2/aruco.hpp>
#include <opencv2/aruco/charuco.hpp>
#include <string>
#include <utility>
#include <vector>

#include "calibration/rigid3.h"

namespace netlab::calib {

enum class PatternType { kChessboard, kCharuco, kMarkers };

struct BoardPattern {
  PatternType type = PatternType::kChessboard;
  int cols = 0, rows = 0;  // chessboard: inner corners; charuco: squares
  double square = 0.0;     // m
  double marker = 0.0;     // m (charuco)
  std::string dictionary;  // charuco / markers: e.g. "DICT_5X5_100"

  std::vector<Eigen::Vector3d> points;          // by id, face frame, m
  std::vector<std::pair<int, int>> neighbours;  // ids one square apart (metric check)
  Eigen::Vector2d extent_min, extent_max;       // printed outline in the face frame, m
  // The side of the face (sign of z in the face frame) from which the print is seen the right way
  // round: -1 when z points into the print (x right, y down as seen), +1 for y up (OpenCV's
  // ChArUco boards may be either).
  double viewer_z = -1.0;
  cv::Ptr<cv::aruco::CharucoBoard> charuco;         // charuco only
  cv::Ptr<cv::aruco::Dictionary> aruco_dictionary;  // charuco and markers

  // A chessboard or ChArUco board; throws std::invalid_argument naming what is wrong.
  static BoardPattern Chessboard(int cols, int rows, double square);
  static BoardPattern Charuco(int cols, int rows, double square, double marker,
                              const std::string& dictionary);
  bool planar() const { return type != PatternType::kMarkers; }
};

struct TargetFace {
  std::string name;  // "board", "front", "back", "markers"
  BoardPattern pattern;
  Rigid3d target_from_face;
};

struct CalibrationTarget {
  enum class Kind { kBoard, kDoubleSidedFoil, kMarkerMap };
  Kind kind = Kind::kBoard;
  std::vector<TargetFace> faces;
  std::vector<std::string> back_cameras;  // foil: cameras that see the back (empty: found)
  double thickness = 0.0;                 // foil, m
  std::string description;

  // Parses a spec string or a YAML file. Throws std::invalid_argument (spec) or InputError
  // (file, with line and key).
  static CalibrationTarget Parse(const std::string& spec);
  static CalibrationTarget Board(BoardPattern pattern);
  // The foil: `pattern` on the front; the back turned about the face's `flip_axis` ('x' or 'y')
  // through `thickness` (m), shifted by `back_offset` (m, front face frame) for misregistration.
  static CalibrationTarget Foil(BoardPattern pattern, double thickness, char flip_axis = 'y',
                                const Eigen::Vector2d& back_offset = Eigen::Vector2d::Zero());
  // A marker map from marker corners (target frame, m), ids 4k..4k+3 for marker id k.
  static CalibrationTarget MarkerMap(
      const std::string& dictionary,
      const std::vector<std::pair<int, std::array<Eigen::Vector3d, 4>>>& markers);
};

// cv::aruco dictionary by name ("DICT_4X4_50" ... "DICT_ARUCO_ORIGINAL"); throws on unknown names.
cv::Ptr<cv::aruco::Dictionary> ArucoDictionary(const std::string& name);

// Corners (OpenCV order) of a square marker of side `size` centred at `center`, printed with its
// x axis along `x_axis` and facing `normal` (towards the viewer).
std::array<Eigen::Vector3d, 4> MarkerCorners(const Eigen::Vector3d& center,
                                             const Eigen::Vector3d& x_axis,
                                             const Eigen::Vector3d& normal, double size);

}  // namespace netlab::calib
