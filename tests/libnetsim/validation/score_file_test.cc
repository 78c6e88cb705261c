#include "libnetsim/validation/score_file.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

#include "common/hdf5_util.h"
#include "tests/libnetsim/validation/score_test_data.h"

namespace netlab::netsim {
namespace {

using testing::ReadDoubles;

std::string Units(hid_t file, const std::string& name) {
  h5::Id dataset(H5Dopen2(file, name.c_str(), H5P_DEFAULT));
  return h5::ReadStringAttribute(dataset.get(), "units");
}

TEST(ScoreFile, HoldsTheResultWithUnitsAndNaNWhereMasked) {
  const auto dir = testing::ScratchDir("netlab_score_file");
  const ScoreResult r = testing::SmallScore();
  const std::string path = (dir / "score.h5").string();
  WriteScore(path, r);
  EXPECT_FALSE(std::filesystem::exists(path + ".partial"));

  h5::Id file = h5::OpenFileReadOnly(path);
  const hid_t f = file.get();
  EXPECT_EQ(h5::ReadStringAttribute(f, "format"), kScoreFileFormat);
  EXPECT_EQ(h5::ReadStringAttribute(f, "verdict"), VerdictName(r.summary.verdict));
  EXPECT_EQ(h5::DatasetDims(f, "/residual"), (std::vector<hsize_t>{200, 36, 3}));
  EXPECT_EQ(Units(f, "/residual"), "m");
  EXPECT_EQ(Units(f, "/time"), "s");
  EXPECT_EQ(Units(f, "/global/corner_area_measured"), "m^2");
  const auto residual = ReadDoubles(f, "/residual");
  const auto d2 = ReadDoubles(f, "/d2");
  // Knot (5,5) = 35 in frame 25 is masked; knot 0 in frame 25 is not.
  EXPECT_TRUE(std::isnan(d2[25 * 36 + 35]));
  EXPECT_TRUE(std::isnan(residual[(25 * 36 + 35) * 3]));
  EXPECT_DOUBLE_EQ(d2[25 * 36], r.d2[25 * 36]);
  EXPECT_DOUBLE_EQ(residual[(25 * 36) * 3 + 2], r.residual[25 * 36].z());
  EXPECT_EQ(ReadDoubles(f, "/knots/rms_m")[7], r.summary.per_knot[7].rms_m);
  EXPECT_EQ(ReadDoubles(f, "/per_class/points")[0], r.summary.per_class[0].points);
  EXPECT_EQ(ReadDoubles(f, "/per_phase/start_s").size(), 4u);
  EXPECT_EQ(ReadDoubles(f, "/alignment/time_offset_s")[0], r.summary.time_offset_s);
  EXPECT_EQ(ReadDoubles(f, "/summary/mean_d2")[0], r.summary.mean_d2);
  EXPECT_EQ(ReadDoubles(f, "/summary/rms_mm")[0], r.summary.rms_m * 1e3);
  EXPECT_EQ(Units(f, "/summary/rms_mm"), "mm");
  const auto rotation = ReadDoubles(f, "/alignment/rotation");  // row-major
  EXPECT_EQ(rotation[1], r.summary.rotation(0, 1));
  std::filesystem::remove_all(dir);
}

TEST(ScoreFile, AnUnwritableFolderIsAnErrorNamingThePath) {
  const ScoreResult r = testing::SmallScore();
  EXPECT_THROW(WriteScore("/nonexistent/folder/score.h5", r), std::runtime_error);
}

}  // namespace
}  // namespace netlab::netsim
