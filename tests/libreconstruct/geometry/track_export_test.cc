#include "libreconstruct/geometry/track_export.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <initializer_list>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "calibration/rig.h"
#include "tests/libreconstruct/test_files.h"

namespace netlab::recon {
namespace {

using testing::ErrorOf;
using testing::Mentions;
using testing::ScratchDir;
using testing::WriteBytes;
namespace fs = std::filesystem;

constexpr int kRows = 2, kCols = 3, kFrames = 4;

// Point number P of knot (row, col) in the export.
int Point(int row, int col) { return row * kCols + col + 1; }

// Tracks of a 2 x 3 net over four frames: the knots stored in an order unlike the points', knot
// (1, 2) missing, some knots not valid in some frames, values with all 17 digits.
KnotTracks Example() {
  KnotTracks tracks;
  tracks.time = {0.0, 0.01, 0.02, 0.03};
  tracks.grid = {{1, 1}, {0, 2}, {0, 0}, {1, 0}, {0, 1}};
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> metres(-3.0, 3.0), px(0.0, 2.0);
  for (int t = 0; t < kFrames; ++t)
    for (int k = 0; k < tracks.knots(); ++k) {
      tracks.position.emplace_back(metres(rng), metres(rng), metres(rng));
      tracks.valid.push_back((t + k) % 3 != 0);
      tracks.reprojection_error_px.push_back(px(rng));
    }
  return tracks;
}

std::string ReadText(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

TEST(XyzPts, RoundTripIsExactWithNanWhereNotValid) {
  ScratchDir dir("track_export");
  const KnotTracks tracks = Example();
  WriteXyzPts(dir / "xyzpts.csv", tracks, kRows, kCols);
  EXPECT_FALSE(fs::exists(dir / "xyzpts.csv.partial"));
  const std::vector<std::vector<Eigen::Vector3d>> read = ReadXyzPts(dir / "xyzpts.csv");
  ASSERT_EQ(read.size(), static_cast<size_t>(kFrames));
  int valid = 0;
  for (int t = 0; t < kFrames; ++t) {
    ASSERT_EQ(read[t].size(), static_cast<size_t>(kRows * kCols));
    for (int k = 0; k < tracks.knots(); ++k) {
      const Eigen::Vector3d& x = read[t][Point(tracks.grid[k][0], tracks.grid[k][1]) - 1];
      if (tracks.Valid(t, k)) {
        EXPECT_EQ(x, tracks.Position(t, k)) << "frame " << t << " knot " << k;
        ++valid;
      } else {
        EXPECT_TRUE(x.array().isNaN().all()) << "frame " << t << " knot " << k;
      }
    }
    EXPECT_TRUE(read[t][Point(1, 2) - 1].array().isNaN().all()) << "missing knot, frame " << t;
  }
  EXPECT_EQ(valid, 13);
}

TEST(XyzRes, RoundTripIsExactWithNanWhereNotValid) {
  ScratchDir dir("track_export");
  const KnotTracks tracks = Example();
  WriteXyzRes(dir / "xyzres.csv", tracks, kRows, kCols);
  EXPECT_FALSE(fs::exists(dir / "xyzres.csv.partial"));
  const std::vector<std::vector<double>> read = ReadXyzRes(dir / "xyzres.csv");
  ASSERT_EQ(read.size(), static_cast<size_t>(kFrames));
  for (int t = 0; t < kFrames; ++t) {
    ASSERT_EQ(read[t].size(), static_cast<size_t>(kRows * kCols));
    for (int k = 0; k < tracks.knots(); ++k) {
      const double residual = read[t][Point(tracks.grid[k][0], tracks.grid[k][1]) - 1];
      if (tracks.Valid(t, k))
        EXPECT_EQ(residual, tracks.reprojection_error_px[t * tracks.knots() + k]);
      else
        EXPECT_TRUE(std::isnan(residual)) << "frame " << t << " knot " << k;
    }
    EXPECT_TRUE(std::isnan(read[t][Point(1, 2) - 1]));
  }
}

TEST(XyzRes, UnknownResidualsAreNan) {
  ScratchDir dir("track_export");
  KnotTracks tracks = Example();
  tracks.reprojection_error_px.clear();
  WriteXyzRes(dir / "xyzres.csv", tracks, kRows, kCols);
  for (const std::vector<double>& row : ReadXyzRes(dir / "xyzres.csv"))
    for (double residual : row) EXPECT_TRUE(std::isnan(residual));
}

TEST(TrackExport, FilesHaveTheDltdv8Layout) {
  ScratchDir dir("track_export");
  KnotTracks tracks;
  tracks.time = {0.0, 1.0};
  tracks.grid = {{0, 0}, {0, 1}};
  tracks.position = {{0.1, -2.0, 3.5}, {1.0, 2.0, 3.0}, {4.0, 5.0, 6.0}, {1e-7, 0.0, -1.25}};
  tracks.valid = {1, 0, 0, 1};
  tracks.reprojection_error_px = {0.5, 9.0, 9.0, 0.1};
  WriteXyzPts(dir / "xyzpts.csv", tracks, 1, 2);
  WriteXyzRes(dir / "xyzres.csv", tracks, 1, 2);
  EXPECT_EQ(ReadText(dir / "xyzpts.csv"),
            "pt1_X,pt1_Y,pt1_Z,pt2_X,pt2_Y,pt2_Z\n"
            "0.10000000000000001,-2,3.5,NaN,NaN,NaN\n"
            "NaN,NaN,NaN,9.9999999999999995e-08,0,-1.25\n");
  EXPECT_EQ(ReadText(dir / "xyzres.csv"),
            "pt1_dltres,pt2_dltres\n"
            "0.5,NaN\n"
            "NaN,0.10000000000000001\n");
}

TEST(TrackExport, RefusesTracksThatDoNotFitTheNet) {
  ScratchDir dir("track_export");
  KnotTracks outside = Example();
  outside.grid[3] = {2, 0};  // row 2 of a 2-row net
  EXPECT_THROW(WriteXyzPts(dir / "xyzpts.csv", outside, kRows, kCols), std::invalid_argument);
  KnotTracks twice = Example();
  twice.grid[3] = twice.grid[0];  // two knots at (1, 1): the tracks hold two nets
  EXPECT_THROW(WriteXyzRes(dir / "xyzres.csv", twice, kRows, kCols), std::invalid_argument);
  KnotTracks short_valid = Example();
  short_valid.valid.pop_back();
  EXPECT_THROW(WriteXyzPts(dir / "xyzpts.csv", short_valid, kRows, kCols), std::invalid_argument);
  EXPECT_TRUE(fs::is_empty(dir.path()));
}

TEST(TrackExport, WriteIntoAMissingFolderFails) {
  ScratchDir dir("track_export");
  EXPECT_THROW(WriteXyzPts(dir / "absent/xyzpts.csv", Example(), kRows, kCols), std::runtime_error);
  EXPECT_FALSE(fs::exists(dir / "absent"));
}

// Reads `text` as an xyzpts (or, with `residuals`, an xyzres) file.
std::string ReadError(const std::string& text, bool residuals = false) {
  ScratchDir dir("track_export_bad");
  WriteBytes(dir / "bad.csv", text);
  return ErrorOf([&] {
    if (residuals)
      ReadXyzRes(dir / "bad.csv");
    else
      ReadXyzPts(dir / "bad.csv");
  });
}

TEST(XyzPts, MalformedFilesAreNamedByLineAndColumn) {
  const std::string header = "pt1_X,pt1_Y,pt1_Z\n";
  EXPECT_TRUE(
      Mentions(ReadError(header + "1,2,3\n4,five,6\n"), {"bad.csv:3:", "'pt1_Y'", "'five'"}));
  EXPECT_TRUE(Mentions(ReadError(header + "1,2,3\n4,5\n"), {"bad.csv:3:", "expected 3 cells"}));
  EXPECT_TRUE(Mentions(ReadError("pt1_X,pt1_Y\n1,2\n"), {"bad.csv:1:", "pt1_Z"}));
  EXPECT_TRUE(Mentions(ReadError("pt1_X,pt1_Y,pt1_W\n1,2,3\n"), {"bad.csv:1:", "'pt1_W'"}));
  EXPECT_TRUE(Mentions(ReadError("pt1_X,pt1_Y,pt1_Z,pt1_Y\n1,2,3,4\n"), {"'pt1_Y'", "twice"}));
  EXPECT_TRUE(Mentions(ReadError("pt0_X,pt0_Y,pt0_Z\n1,2,3\n"), {"'pt0_X'"}));
  EXPECT_TRUE(Mentions(ErrorOf([] { ReadXyzPts("/nonexistent/xyzpts.csv"); }),
                       {"/nonexistent/xyzpts.csv"}));
}

TEST(XyzRes, MalformedFilesAreNamedByLineAndColumn) {
  EXPECT_TRUE(Mentions(ReadError("pt1_dltres,pt2_dltres\n0.5,1e999\n", true),
                       {"bad.csv:2:", "'pt2_dltres'", "'1e999'"}));
  EXPECT_TRUE(Mentions(ReadError("pt1_dltres,pt2_X\n0.5,1\n", true), {"bad.csv:1:", "'pt2_X'"}));
  EXPECT_TRUE(Mentions(ReadError("pt1_dltres\n0.5,1\n", true), {"bad.csv:2:", "got 2"}));
}

// A 2 x 3 net's reconstruction over frames 4 and 5, knot 4 not valid in frame 5, one outlier.
SequenceResult ExampleResult() {
  SequenceResult r;
  r.rows = kRows;
  r.cols = kCols;
  r.frame_index = {4, 5};
  r.rig = calib::PaperRig();
  for (int i = 0; i < 2 * kRows * kCols; ++i) {
    r.position.emplace_back(i, 0.5 * i, -i);
    r.valid.push_back(i != kRows * kCols + 4);
    r.covariance.push_back(Eigen::Matrix3d::Identity() * (i + 1));
    r.rms_px.push_back(0.1 * i);
  }
  r.outliers.push_back({5, 2, 1, 7.5});
  return r;
}

TEST(TracksFromSequence, CarriesEveryFieldWithTimeFromTheFrameRateAndKnotsRowMajor) {
  const SequenceResult r = ExampleResult();
  const KnotTracks tracks = TracksFromSequence(r, 100.0, "a test");
  EXPECT_NO_THROW(tracks.CheckConsistent());
  EXPECT_EQ(tracks.source, "a test");
  EXPECT_EQ(tracks.time, (std::vector<double>{0.04, 0.05}));
  EXPECT_EQ(tracks.frame_index, r.frame_index);
  ASSERT_EQ(tracks.knots(), kRows * kCols);
  EXPECT_EQ(tracks.grid[4], (std::array<int, 2>{1, 1}));
  EXPECT_EQ(tracks.FindKnot(1, 2), 5);
  EXPECT_EQ(tracks.Position(1, 3), Eigen::Vector3d(9, 4.5, -9));
  EXPECT_FALSE(tracks.Valid(1, 4));
  EXPECT_EQ(tracks.covariance, r.covariance);
  EXPECT_EQ(tracks.reprojection_error_px, r.rms_px);
  ASSERT_EQ(tracks.camera_names.size(), r.rig.cameras.size());
  EXPECT_EQ(tracks.camera_names[3], r.rig.cameras[3].name);
  ASSERT_EQ(tracks.outliers.size(), 1u);
  EXPECT_EQ(tracks.outliers[0].frame, 5);
  EXPECT_EQ(tracks.outliers[0].knot, 2);
  EXPECT_EQ(tracks.outliers[0].camera, 1);
  EXPECT_EQ(tracks.outliers[0].residual_px, 7.5);
}

// True tracks of a 2 x 3 net sampled at 0, 0.1, 0.2 s, every knot moving at (1, 2, 0) m/s from
// (row, col, 0).
KnotTracks Truth() {
  KnotTracks truth;
  truth.time = {0.0, 0.1, 0.2};
  for (int row = 0; row < kRows; ++row)
    for (int col = 0; col < kCols; ++col) truth.grid.push_back({row, col});
  for (double t : truth.time)
    for (const auto& [row, col] : truth.grid) {
      truth.position.emplace_back(row + t, col + 2.0 * t, 0.0);
      truth.valid.push_back(1);
    }
  return truth;
}

// Measured tracks between the truth's samples: true positions through `motion`; covariances
// diag(var) (m^2).
KnotTracks Measured(const std::vector<double>& times,
                    const std::function<Eigen::Vector3d(const Eigen::Vector3d&)>& motion,
                    double var) {
  KnotTracks tracks = Truth();
  tracks.time = times;
  tracks.position.clear();
  tracks.valid.clear();
  for (double t : times)
    for (const auto& [row, col] : tracks.grid) {
      tracks.position.push_back(motion(Eigen::Vector3d(row + t, col + 2.0 * t, 0.0)));
      tracks.valid.push_back(1);
      tracks.covariance.push_back(var * Eigen::Matrix3d::Identity());
    }
  return tracks;
}

TEST(CompareWithTruth, AnOffsetIsTheFramesDifferenceNotAnError) {
  // Every point 3 mm off along y, between the truth's samples: in the truth's frame no error,
  // and the motion that takes the tracks there is the 3 mm.
  const Eigen::Vector3d offset(0.0, 0.003, 0.0);
  const KnotTracks tracks = Measured(
      {0.05, 0.125}, [&](const Eigen::Vector3d& p) { return Eigen::Vector3d(p + offset); },
      0.5 * 0.003 * 0.003);
  const TruthComparison c = CompareWithTruth(tracks, Truth());
  EXPECT_EQ(c.points, 2 * kRows * kCols);
  EXPECT_TRUE(c.aligned);
  EXPECT_NEAR(c.rms_m, 0.0, 1e-9);
  EXPECT_NEAR(c.max_m, 0.0, 1e-9);
  EXPECT_NEAR(c.translation_m, 0.003, 1e-9);
  EXPECT_NEAR(c.rotation_deg, 0.0, 1e-6);
}

TEST(CompareWithTruth, ErrorsAndMahalanobisInTheTruthsFrame) {
  // Errors along z of 1, -2, 1 mm across each row of the flat net (z = 0): no rigid motion
  // explains any of them (their mean and their moments along the rows and columns are zero), so
  // they are the errors in the truth's frame. Covariance (3 mm)^2 / 2 per axis.
  const double var = 0.5 * 0.003 * 0.003;
  KnotTracks tracks = Measured(
      {0.05, 0.125}, [](const Eigen::Vector3d& p) { return p; }, var);
  for (int t = 0; t < 2; ++t)
    for (int k = 0; k < kRows * kCols; ++k)
      tracks.position[static_cast<size_t>(t) * kRows * kCols + k].z() +=
          (tracks.grid[k][1] == 1 ? -2e-3 : 1e-3);
  const TruthComparison c = CompareWithTruth(tracks, Truth());
  ASSERT_TRUE(c.aligned);
  EXPECT_NEAR(c.rms_m, std::sqrt(2.0) * 1e-3, 1e-9);
  EXPECT_NEAR(c.max_m, 2e-3, 1e-9);
  EXPECT_NEAR(c.mean_mahalanobis2, 2e-6 / var, 1e-6);
  EXPECT_NEAR(c.translation_m, 0.0, 1e-9);
}

TEST(CompareWithTruth, ARigidMotionVanishesAfterAlignment) {
  // The truth turned by 0.1 rad about z and moved: large errors, none after the best motion.
  const Eigen::Matrix3d turn = Eigen::AngleAxisd(0.1, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  const KnotTracks tracks = Measured(
      {0.0, 0.1, 0.2},
      [&](const Eigen::Vector3d& p) {
        return Eigen::Vector3d(turn * p + Eigen::Vector3d(1.0, 0.0, 0.0));
      },
      1e-6);
  const TruthComparison c = CompareWithTruth(tracks, Truth());
  EXPECT_EQ(c.points, 3 * kRows * kCols);
  EXPECT_NEAR(c.rms_m, 0.0, 1e-9);
  EXPECT_NEAR(c.rotation_deg, 0.1 * 180 / M_PI, 1e-6);
}

TEST(CompareWithTruth, LeavesOutPointsTheTruthCannotGive) {
  // Frame 0 before the truth's span, frame 2 after it; in frame 1 knot 0 not valid, knot 1 at a
  // grid position the truth lacks, and knot 2 between a valid and an invalid true sample.
  KnotTracks tracks = Measured(
      {-0.01, 0.15, 0.21}, [](const Eigen::Vector3d& p) { return p; }, 1e-6);
  tracks.valid[kRows * kCols + 0] = 0;
  tracks.grid[1] = {5, 5};
  KnotTracks truth = Truth();
  truth.valid[2 * kRows * kCols + 2] = 0;
  const TruthComparison c = CompareWithTruth(tracks, truth);
  EXPECT_EQ(c.points, kRows * kCols - 3);
  EXPECT_NEAR(c.rms_m, 0.0, 1e-9);
  // Fewer than three points: no frame to compare in, no numbers; none at all: zeros.
  tracks.valid.assign(tracks.valid.size(), 0);
  tracks.valid[kRows * kCols + 3] = tracks.valid[kRows * kCols + 4] = 1;
  tracks.position[kRows * kCols + 3].z() += 0.004;
  const TruthComparison two = CompareWithTruth(tracks, truth);
  EXPECT_EQ(two.points, 2);
  EXPECT_FALSE(two.aligned);
  EXPECT_EQ(two.rms_m, 0.0);
  EXPECT_EQ(two.max_m, 0.0);
  tracks.valid.assign(tracks.valid.size(), 0);
  const TruthComparison none = CompareWithTruth(tracks, truth);
  EXPECT_EQ(none.points, 0);
  EXPECT_EQ(none.rms_m, 0.0);
  EXPECT_EQ(none.mean_mahalanobis2, 0.0);
}

}  // namespace
}  // namespace netlab::recon
