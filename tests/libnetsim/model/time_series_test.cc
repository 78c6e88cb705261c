#include "libnetsim/model/time_series.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

namespace netlab::netsim {
namespace {

std::string WriteTemp(const std::string& name, const std::string& text) {
  const auto path = std::filesystem::temp_directory_path() / (std::to_string(getpid()) + name);
  std::ofstream(path) << text;
  return path.string();
}

TEST(TimeSeries, InterpolatesLinearlyAndHoldsTheEnds) {
  const TimeSeries3 s({0.0, 1.0, 3.0}, {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(2, 0, 0),
                                        Eigen::Vector3d(2, 4, 0)});
  EXPECT_NEAR(s.Value(0.5).x(), 1.0, 1e-15);
  EXPECT_NEAR(s.Value(2.0).y(), 2.0, 1e-15);
  EXPECT_EQ(s.Value(-1.0), Eigen::Vector3d(0, 0, 0));
  EXPECT_EQ(s.Value(9.0), Eigen::Vector3d(2, 4, 0));
  EXPECT_NEAR(s.Rate(0.5).x(), 2.0, 1e-15);
  EXPECT_NEAR(s.Rate(2.0).y(), 2.0, 1e-15);
  EXPECT_EQ(s.Rate(5.0), Eigen::Vector3d::Zero());
}

TEST(TimeSeries, ReadsCsvWithHeaderCommentsAndBlankLines) {
  const auto path = WriteTemp("ts_ok.csv", "# gyro\nt,wx,wy,wz\n\n0, 1, 2, 3\n0.5 4 5 6\n");
  const TimeSeries3 s = TimeSeries3::ReadCsv(path);
  EXPECT_EQ(s.size(), 2u);
  EXPECT_NEAR(s.Value(0.25).z(), 4.5, 1e-15);
}

TEST(TimeSeries, NonIncreasingTimeIsReportedWithItsLine) {
  const auto path = WriteTemp("ts_bad_time.csv", "t,x,y,z\n0,0,0,0\n1,0,0,0\n0.5,0,0,0\n");
  try {
    TimeSeries3::ReadCsv(path);
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(":4:"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("does not increase"), std::string::npos) << e.what();
  }
}

TEST(TimeSeries, WrongColumnCountIsReportedWithItsLine) {
  const auto path = WriteTemp("ts_bad_cols.csv", "0,0,0,0\n1,0,0\n");
  try {
    TimeSeries3::ReadCsv(path);
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(":2:"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("expected 4 numbers"), std::string::npos) << e.what();
  }
}

TEST(TimeSeries, EmptyOrMissingFilesAreErrors) {
  EXPECT_THROW(TimeSeries3::ReadCsv(WriteTemp("ts_empty.csv", "# nothing\n")), std::runtime_error);
  EXPECT_THROW(TimeSeries3::ReadCsv("/nonexistent/gyro.csv"), std::runtime_error);
}

}  // namespace
}  // namespace netlab::netsim
