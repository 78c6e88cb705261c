#include "calibration/target.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

namespace netlab::calib {
namespace {

std::string ErrorOf(const std::string& spec) {
  try {
    CalibrationTarget::Parse(spec);
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}

std::string WriteTemp(const std::string& name, const std::string& text) {
  const auto path = std::filesystem::temp_directory_path() / (std::to_string(getpid()) + name);
  std::ofstream(path) << text;
  return path.string();
}

TEST(Target, ParsesChessboardSpec) {
  const CalibrationTarget t = CalibrationTarget::Parse("chessboard:9x6:0.05");
  ASSERT_EQ(t.faces.size(), 1u);
  const BoardPattern& p = t.faces[0].pattern;
  EXPECT_EQ(p.points.size(), 54u);
  EXPECT_NEAR(p.points[53].x(), 8 * 0.05, 1e-12);
  EXPECT_NEAR(p.points[53].y(), 5 * 0.05, 1e-12);
  EXPECT_EQ(p.neighbours.size(), 8u * 6 + 9u * 5);
}

TEST(Target, ParsesCharucoSpec) {
  const CalibrationTarget t = CalibrationTarget::Parse("charuco:10x7:0.04:0.03:DICT_5X5_100");
  EXPECT_EQ(t.faces[0].pattern.points.size(), 9u * 6);
  EXPECT_NEAR(t.faces[0].pattern.extent_max.x(), 0.4, 1e-12);
}

TEST(Target, BadSpecsSayWhatIsWrong) {
  EXPECT_NE(ErrorOf("chessboard:9-6:0.05").find("expected COLSxROWS"), std::string::npos);
  EXPECT_NE(ErrorOf("chessboard:8x6:0.05").find("odd by even"), std::string::npos);
  EXPECT_NE(ErrorOf("chessboard:9x6:-1").find("SQUARE must be a positive length"),
            std::string::npos);
  EXPECT_NE(ErrorOf("charuco:10x7:0.04:0.05:DICT_5X5_100").find("marker < square"),
            std::string::npos);
  EXPECT_NE(ErrorOf("charuco:10x7:0.04:0.03:DICT_9X9").find("unknown ArUco dictionary"),
            std::string::npos);
  EXPECT_NE(ErrorOf("charuco:20x20:0.04:0.03:DICT_4X4_50").find("needs 200 markers"),
            std::string::npos);
  EXPECT_NE(ErrorOf("/no/such/board.yaml").find("not chessboard"), std::string::npos);
}

// The back of the foil is the front print turned about y, mirrored about the print's centre line
// and one thickness behind: a back point lands where its mirror image is on the front.
TEST(Target, FoilBackMirrorsTheFrontThroughItsThickness) {
  const BoardPattern p = BoardPattern::Chessboard(9, 6, 0.05);
  const CalibrationTarget foil = CalibrationTarget::Foil(p, 0.002);
  ASSERT_EQ(foil.faces.size(), 2u);
  const Rigid3d& target_from_back = foil.faces[1].target_from_face;
  for (int r = 0; r < 6; ++r)
    for (int c = 0; c < 9; ++c) {
      const Eigen::Vector3d back = target_from_back * p.points[r * 9 + c];
      const Eigen::Vector3d mirror = p.points[r * 9 + (8 - c)];
      EXPECT_NEAR(back.x(), mirror.x(), 1e-12);
      EXPECT_NEAR(back.y(), mirror.y(), 1e-12);
      EXPECT_NEAR(back.z(), 0.002, 1e-12);  // behind the front surface, away from its viewer
    }
  // Proper rotation whose z axis points back at the front's viewer side.
  EXPECT_NEAR(target_from_back.RotationMatrix().determinant(), 1.0, 1e-12);
  EXPECT_NEAR((target_from_back.rotation * Eigen::Vector3d::UnitZ()).z(), -1.0, 1e-12);
}

TEST(Target, ParsesFoilAndMarkerMapFiles) {
  const std::string foil = WriteTemp("foil.yaml",
                                     "type: double_sided_foil\n"
                                     "board: {type: charuco, cols: 8, rows: 6, square: 0.05, "
                                     "marker: 0.037, dictionary: DICT_5X5_100}\n"
                                     "thickness: 0.0005\n"
                                     "back_cameras: [cam2, cam3]\n");
  const CalibrationTarget f = CalibrationTarget::Parse(foil);
  EXPECT_EQ(f.kind, CalibrationTarget::Kind::kDoubleSidedFoil);
  EXPECT_EQ(f.back_cameras, (std::vector<std::string>{"cam2", "cam3"}));
  const std::string map = WriteTemp("map.yaml",
                                    "type: marker_map\n"
                                    "dictionary: DICT_4X4_50\n"
                                    "markers:\n"
                                    "  - {id: 3, center: [1, 0, 0], x_axis: [0, 1, 0], "
                                    "normal: [-1, 0, 0], size: 0.1}\n"
                                    "  - {id: 7, corners: [[0, 0, 1], [0.1, 0, 1], [0.1, 0.1, 1], "
                                    "[0, 0.1, 1]]}\n");
  const CalibrationTarget m = CalibrationTarget::Parse(map);
  EXPECT_EQ(m.kind, CalibrationTarget::Kind::kMarkerMap);
  const auto& points = m.faces[0].pattern.points;
  ASSERT_EQ(points.size(), 32u);
  EXPECT_NEAR((points[12] - points[13]).norm(), 0.1, 1e-12);  // marker 3's top edge
  EXPECT_NEAR(points[29].x(), 0.1, 1e-12);                    // marker 7's corner 1
}

TEST(Target, BadFilesNameTheLineAndKey) {
  const std::string path = WriteTemp("bad_foil.yaml",
                                     "type: double_sided_foil\n"
                                     "board: {type: chessboard, cols: 9, rows: 6, square: 0.05}\n"
                                     "thicknes: 0.0005\n");
  const std::string error = ErrorOf(path);
  EXPECT_NE(error.find(":3: thicknes: unknown key"), std::string::npos) << error;
  const std::string map = WriteTemp("bad_map.yaml",
                                    "type: marker_map\ndictionary: DICT_4X4_50\n"
                                    "markers:\n  - {id: 99, center: [0, 0, 0], x_axis: [1, 0, 0], "
                                    "normal: [0, 0, 1], size: 0.1}\n");
  EXPECT_NE(ErrorOf(map).find("id 99 is not in DICT_4X4_50"), std::string::npos) << ErrorOf(map);
}

TEST(Target, MarkerCornersAreASquareFacingTheNormal) {
  const auto c = MarkerCorners(Eigen::Vector3d(1, 2, 3), Eigen::Vector3d(0, 1, 0),
                               Eigen::Vector3d(-1, 0, 0), 0.2);
  EXPECT_NEAR((c[1] - c[0]).norm(), 0.2, 1e-12);
  EXPECT_NEAR((c[3] - c[0]).norm(), 0.2, 1e-12);
  EXPECT_NEAR((c[1] - c[0]).dot(Eigen::Vector3d(0, 1, 0)), 0.2, 1e-12);
  // Top-left -> top-right -> bottom-left turns clockwise seen from the normal's side.
  const Eigen::Vector3d n = (c[1] - c[0]).cross(c[3] - c[0]);
  EXPECT_LT(n.dot(Eigen::Vector3d(-1, 0, 0)), 0.0);
}

}  // namespace
}  // namespace netlab::calib
