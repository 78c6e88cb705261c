#include "common/tracks/track_file.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <stdexcept>

#include "common/hdf5_util.h"

namespace netlab {
namespace {

class TrackFile : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() /
           ("netlab_track_" + std::to_string(getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  std::string Path(const std::string& name) const { return (dir_ / name).string(); }

  std::filesystem::path dir_;
};

KnotTracks Example() {
  KnotTracks t;
  t.time = {0.0, 0.1, 0.2};
  t.grid = {{0, 0}, {0, 1}};
  t.net_names = {"net"};
  t.net = {0, 0};
  for (int f = 0; f < 3; ++f)
    for (int k = 0; k < 2; ++k) {
      t.position.emplace_back(f, k, 0.5 * f * k);
      t.valid.push_back(f == 1 && k == 1 ? 0 : 1);
      t.covariance.push_back(Eigen::Matrix3d::Identity() * (1e-6 * (f + 1)));
      t.reprojection_error_px.push_back(0.1 * f + k);
    }
  t.source = "netlab triangulate";
  t.frame_index = {10, 11, 12};
  t.camera_names = {"cam0", "cam1"};
  t.outliers = {{11, 1, 0, 23.5}, {12, 0, 1, std::nan("")}};
  t.contact_start_s = 0.15;
  return t;
}

TEST_F(TrackFile, RoundTripKeepsEverything) {
  const KnotTracks in = Example();
  WriteKnotTracks(Path("tracks.h5"), in);
  const KnotTracks out = ReadKnotTracks(Path("tracks.h5"));
  EXPECT_EQ(out.time, in.time);
  EXPECT_EQ(out.grid, in.grid);
  EXPECT_EQ(out.net, in.net);
  EXPECT_EQ(out.net_names, in.net_names);
  EXPECT_EQ(out.position, in.position);
  EXPECT_EQ(out.valid, in.valid);
  EXPECT_EQ(out.covariance.size(), 6u);
  EXPECT_TRUE(out.covariance[5].isApprox(in.covariance[5]));
  EXPECT_EQ(out.reprojection_error_px, in.reprojection_error_px);
  EXPECT_EQ(out.source, "netlab triangulate");
  EXPECT_EQ(out.frame_index, in.frame_index);
  EXPECT_EQ(out.camera_names, in.camera_names);
  ASSERT_EQ(out.outliers.size(), 2u);
  EXPECT_EQ(out.outliers[0].frame, 11);
  EXPECT_EQ(out.outliers[0].knot, 1);
  EXPECT_EQ(out.outliers[0].camera, 0);
  EXPECT_EQ(out.outliers[0].residual_px, 23.5);
  EXPECT_EQ(out.outliers[1].camera, 1);
  EXPECT_TRUE(std::isnan(out.outliers[1].residual_px));
  EXPECT_FALSE(out.Valid(1, 1));
  EXPECT_EQ(out.FindKnot(0, 1), 1);
  EXPECT_EQ(out.contact_start_s, 0.15);
  EXPECT_FALSE(std::filesystem::exists(Path("tracks.h5.partial")));
}

TEST_F(TrackFile, StreamingWriterCommitsWhenDone) {
  TrackFileWriter::Layout layout;
  layout.nodes = 3;
  layout.grid = {{0, 0}};
  layout.probe_names = {"tip"};
  layout.scenario = "name: x\n";
  {
    TrackFileWriter writer(Path("sim.h5"), layout);
    for (int f = 0; f < 100; ++f) {
      const std::vector<Eigen::Vector3d> nodes(3, Eigen::Vector3d(f, 0, 0));
      writer.AppendFrame(0.01 * f, nodes, {nodes[0]}, {nodes[2]});
    }
    EXPECT_TRUE(std::filesystem::exists(Path("sim.h5.partial")));
    EXPECT_FALSE(std::filesystem::exists(Path("sim.h5")));
    writer.Commit();
  }
  const KnotTracks tracks = ReadKnotTracks(Path("sim.h5"));
  EXPECT_EQ(tracks.frames(), 100);
  EXPECT_EQ(tracks.Position(42, 0), Eigen::Vector3d(42, 0, 0));
  EXPECT_EQ(tracks.scenario, "name: x\n");
  EXPECT_EQ(tracks.source, "netlab simulate");
  const auto nodes = ReadNodePositions(Path("sim.h5"));
  ASSERT_EQ(nodes.size(), 100u);
  EXPECT_EQ(nodes[99][2], Eigen::Vector3d(99, 0, 0));
}

TEST_F(TrackFile, InterruptedWriteLeavesThePreviousFileIntact) {
  WriteKnotTracks(Path("tracks.h5"), Example());
  TrackFileWriter::Layout layout;
  layout.grid = {{0, 0}};
  {
    TrackFileWriter writer(Path("tracks.h5"), layout);
    writer.AppendFrame(0.0, {}, {Eigen::Vector3d::Zero()}, {});
    // destroyed without Commit: a crash or a blow-up mid-run
  }
  EXPECT_EQ(ReadKnotTracks(Path("tracks.h5")).frames(), 3);
  EXPECT_TRUE(std::filesystem::exists(Path("tracks.h5.partial")));
}

TEST_F(TrackFile, MissingFileIsNamed) {
  try {
    ReadKnotTracks(Path("absent.h5"));
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("absent.h5"), std::string::npos);
  }
}

TEST_F(TrackFile, TextFileIsNotHdf5) {
  std::ofstream(Path("notes.h5")) << "not hdf5\n";
  try {
    ReadKnotTracks(Path("notes.h5"));
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("not an HDF5 file"), std::string::npos) << e.what();
  }
}

TEST_F(TrackFile, TruncatedFileIsAnError) {
  WriteKnotTracks(Path("tracks.h5"), Example());
  std::filesystem::resize_file(Path("tracks.h5"), 600);
  EXPECT_THROW(ReadKnotTracks(Path("tracks.h5")), std::runtime_error);
}

TEST_F(TrackFile, MismatchedShapesAreNamed) {
  KnotTracks t = Example();
  t.position.pop_back();
  EXPECT_THROW(WriteKnotTracks(Path("bad.h5"), t), std::invalid_argument);
}

// A "units" attribute is honoured (docs/bad_input.md): ms, mm and mm^2 are converted to s, m and
// m^2, and a unit netlab does not know is refused by file, dataset and units (mm read as m made a
// net 1000 times larger).
TEST_F(TrackFile, UnitsAttributesAreConvertedOrRefused) {
  KnotTracks in = Example();
  KnotTracks scaled = in;
  for (double& t : scaled.time) t *= 1e3;
  for (Eigen::Vector3d& p : scaled.position) p *= 1e3;
  for (Eigen::Matrix3d& c : scaled.covariance) c *= 1e6;
  scaled.contact_start_s *= 1e3;
  WriteKnotTracks(Path("mm.h5"), scaled);
  {
    h5::Id file = h5::OpenFileReadWrite(Path("mm.h5"));
    h5::SetUnits(file.get(), "time", "ms");
    h5::SetUnits(file.get(), "contact_start", "ms");
    h5::SetUnits(file.get(), "knots/position", "mm");
    h5::SetUnits(file.get(), "knots/covariance", "mm^2");
  }
  const KnotTracks out = ReadKnotTracks(Path("mm.h5"));
  for (size_t i = 0; i < in.time.size(); ++i) EXPECT_NEAR(out.time[i], in.time[i], 1e-15);
  for (size_t i = 0; i < in.position.size(); ++i)
    EXPECT_TRUE(out.position[i].isApprox(in.position[i], 1e-12) ||
                (out.position[i] - in.position[i]).norm() < 1e-15)
        << i;
  EXPECT_TRUE(out.covariance[5].isApprox(in.covariance[5], 1e-12));
  EXPECT_NEAR(out.contact_start_s, in.contact_start_s, 1e-15);

  WriteKnotTracks(Path("feet.h5"), in);
  {
    h5::Id file = h5::OpenFileReadWrite(Path("feet.h5"));
    h5::SetUnits(file.get(), "knots/position", "ft");
  }
  try {
    ReadKnotTracks(Path("feet.h5"));
    FAIL() << "positions in feet were read";
  } catch (const std::runtime_error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(Path("feet.h5") + ":/knots/position has units 'ft'"), std::string::npos)
        << what;
    EXPECT_NE(what.find("mm"), std::string::npos) << what;
  }
}

}  // namespace
}  // namespace netlab
