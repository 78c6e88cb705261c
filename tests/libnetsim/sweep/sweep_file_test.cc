// sweep.h5 is written to sweep.h5.partial and renamed into place by Commit: until then a previous
// file is untouched, and a writer dropped without Commit (a failed sweep) leaves it so.

#include "libnetsim/sweep/sweep_file.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "common/hdf5_util.h"

namespace netlab::netsim {
namespace {

class SweepFile : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() /
           ("sweep_file_test_" + std::to_string(getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    std::filesystem::create_directories(dir_);
    path_ = (dir_ / "sweep.h5").string();
    std::ofstream(path_) << "the previous sweep";
    header_.scenario_path = "net.yaml";
    header_.scenario_text = "name: net\n";
    header_.parameters = {ParseVary("duration=0.1:0.2:2")};
    header_.grid = SweepGrid({}, header_.parameters);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  std::string Previous() const {
    std::stringstream s;
    s << std::ifstream(path_).rdbuf();
    return s.str();
  }
  SweepRun Run(int index) const {
    SweepRun run;
    run.index = index;
    run.time = {0.0, 0.1};
    run.grid = {{0, 0}, {0, 1}};
    run.net = {0, 0};
    run.knots = {Vector3d(0, 0, 0), Vector3d(1, 0, 0), Vector3d(0, 0, 1), Vector3d(1, 0, 1)};
    run.outputs.max_area_m2 = index + 1.0;
    return run;
  }
  std::filesystem::path dir_;
  std::string path_;
  SweepFileHeader header_;
};

TEST_F(SweepFile, WritesToPartialThenRenames) {
  {
    SweepFileWriter writer(path_, header_);
    EXPECT_TRUE(std::filesystem::exists(path_ + ".partial"));
    writer.AddRun(Run(1));
    writer.AddRun(Run(0));
    EXPECT_EQ(Previous(), "the previous sweep");
    SweepResult result;
    result.runs = {Run(0), Run(1)};
    writer.Commit(result, ComputeSensitivities(header_.parameters, result.runs));
  }
  EXPECT_FALSE(std::filesystem::exists(path_ + ".partial"));
  std::lock_guard<std::mutex> lock(h5::Mutex());
  h5::Id f = h5::OpenFileReadOnly(path_);
  double area[2];
  h5::ReadDataset(f.get(), "runs/max_area", H5T_NATIVE_DOUBLE, area);
  EXPECT_EQ(area[0], 1.0);  // by run index, whatever the order they came in
  EXPECT_EQ(area[1], 2.0);
  EXPECT_EQ(h5::DatasetDims(f.get(), "tracks/1/knots/position"), (std::vector<hsize_t>{2, 2, 3}));
  EXPECT_EQ(h5::ReadStringAttribute(f.get(), "format"), "netlab-sweep");
}

// Each parameter's values carry its unit, one line per parameter in the order of the paths (they
// were all called dimensionless, "1").
TEST_F(SweepFile, EachParameterHasItsUnit) {
  header_.parameters = {ParseVary("duration=0.1:0.2:2"), ParseVary("nets.0.velocity.0=1:2:2"),
                        ParseVary("materials.nylon.bend_stiffness=1e-4:2e-4:2"),
                        ParseVary("nets.0.segments_per_link=2:3:2")};
  header_.grid = SweepGrid({}, header_.parameters);
  {
    SweepFileWriter writer(path_, header_);
    SweepResult result;
    for (int i = 0; i < static_cast<int>(header_.grid.size()); ++i) {
      result.runs.push_back(Run(i));
      writer.AddRun(result.runs.back());
    }
    writer.Commit(result, ComputeSensitivities(header_.parameters, result.runs));
  }
  std::lock_guard<std::mutex> lock(h5::Mutex());
  h5::Id f = h5::OpenFileReadOnly(path_);
  for (const char* name : {"parameters/from", "parameters/to", "runs/values"}) {
    h5::Id dataset(H5Dopen2(f.get(), name, H5P_DEFAULT));
    EXPECT_EQ(h5::ReadStringAttribute(dataset.get(), "units"), "s\nm/s\nN m^2\n1") << name;
  }
}

TEST_F(SweepFile, WithoutCommitThePreviousFileStays) {
  {
    SweepFileWriter writer(path_, header_);
    writer.AddRun(Run(0));
  }
  EXPECT_EQ(Previous(), "the previous sweep");
}

}  // namespace
}  // namespace netlab::netsim
