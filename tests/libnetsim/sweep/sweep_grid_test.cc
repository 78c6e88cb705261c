// The grid of `netlab sweep --vary`: parsing a:b:n, the values, the order of the runs, the check
// of the paths against the scenario.

#include "libnetsim/sweep/sweep_grid.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "common/errors.h"

namespace netlab::netsim {
namespace {

std::string ErrorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(ParseVary, ReadsPathFromToAndCount) {
  const SweepParameter p = ParseVary("materials.nylon_1mm.bend_stiffness=1e-4:4e-4:4");
  EXPECT_EQ(p.path, "materials.nylon_1mm.bend_stiffness");
  EXPECT_EQ(p.from, 1e-4);
  EXPECT_EQ(p.to, 4e-4);
  EXPECT_EQ(p.count, 4);
  const std::vector<double> v = p.Values();
  ASSERT_EQ(v.size(), 4u);
  EXPECT_EQ(v.front(), 1e-4);
  EXPECT_EQ(v[1], 2e-4);  // as typed, not 1e-4 + (4e-4 - 1e-4) / 3 = 0.00019999999999999998
  EXPECT_EQ(v[2], 3e-4);
  EXPECT_EQ(v.back(), 4e-4);  // exactly the end the user named
  EXPECT_EQ(ParseVary("drag.drag_coefficient = 1.2:0.8:3").Values()[1], 1.0);  // descending
  EXPECT_EQ(ParseVary("duration=0.5:0.5:1").Values(), std::vector<double>{0.5});
}

TEST(ParseVary, MalformedArgumentsAreErrorsNamingThem) {
  EXPECT_NE(ErrorOf([] { ParseVary("bend_stiffness"); })
                .find("--vary 'bend_stiffness': expected "
                      "PATH=a:b:n"),
            std::string::npos);
  EXPECT_NE(ErrorOf([] { ParseVary("=1:2:3"); }).find("expected PATH=a:b:n"), std::string::npos);
  EXPECT_NE(ErrorOf([] { ParseVary("a.b=1:2"); })
                .find("--vary 'a.b=1:2': expected a:b:n after "
                      "'=' (from a to b in n values), got 2 "
                      "fields"),
            std::string::npos);
  EXPECT_NE(ErrorOf([] { ParseVary("a.b=1:2:3:4"); }).find("got 4 fields"), std::string::npos);
  EXPECT_NE(ErrorOf([] { ParseVary("a.b=x:2:3"); }).find("a = 'x' is not a number"),
            std::string::npos);
  EXPECT_NE(ErrorOf([] { ParseVary("a.b=1:nan:3"); }).find("b = 'nan' is not a number"),
            std::string::npos);
  EXPECT_NE(ErrorOf([] { ParseVary("a.b=1:2:2.5"); }).find("n = '2.5' is not a whole number"),
            std::string::npos);
  EXPECT_NE(ErrorOf([] { ParseVary("a.b=1:2:0"); }).find("n = 0: need at least 1 value"),
            std::string::npos);
  EXPECT_NE(ErrorOf([] { ParseVary("a.b=1:2:-3"); }).find("n = -3: need at least 1 value"),
            std::string::npos);
  EXPECT_NE(ErrorOf([] { ParseVary("a.b=1:2:1"); }).find("n = 1 takes the one value a"),
            std::string::npos);
  EXPECT_NE(ErrorOf([] { ParseVary("a.b=1:2:"); }).find("n = '' is not a whole number"),
            std::string::npos);
}

TEST(ValueText, ReadsBackAsTheSameDouble) {
  for (double v : {1e-4, 2.0000000000000001e-4, 0.1 + 0.2, 1.0 / 3.0, 1178.0, -2.5e-12}) {
    const std::string text = ValueText(v);
    EXPECT_EQ(std::strtod(text.c_str(), nullptr), v) << text;
  }
  EXPECT_EQ(ValueText(1e-4), "1e-04");
  EXPECT_EQ(ValueText(2.5e-3), "0.0025");
  EXPECT_EQ(ValueText(1178.0), "1178");
}

// --ensemble N: N runs, each parameter at one of its values, each value equally often (within
// one), the parameters shuffled apart, the same runs every time; fewer than 2 runs refused.
TEST(SweepEnsemble, EachValueEquallyOftenShuffledAndRepeatable) {
  const std::vector<SweepParameter> parameters = {ParseVary("integrator.dt=1e-5:4e-5:4"),
                                                  ParseVary("nets.0.segments_per_link=2:3:2")};
  const std::vector<SweepPoint> runs = SweepEnsemble({{"duration", "0.1"}}, parameters, 10);
  ASSERT_EQ(runs.size(), 10u);
  std::vector<int> dt_count(4, 0), seg_count(2, 0);
  for (int i = 0; i < 10; ++i) {
    EXPECT_EQ(runs[i].index, i);
    ASSERT_EQ(runs[i].overrides.size(), 3u);
    EXPECT_EQ(runs[i].overrides[0].path, "duration");
    EXPECT_EQ(runs[i].values[0], parameters[0].Values()[runs[i].value_index[0]]);
    dt_count[runs[i].value_index[0]]++;
    seg_count[runs[i].value_index[1]]++;
  }
  for (int c : dt_count) EXPECT_TRUE(c == 2 || c == 3) << c;
  EXPECT_EQ(seg_count[0], 5);
  EXPECT_EQ(seg_count[1], 5);
  // Not the grid's order, and the same on a second call.
  bool grid_order = true;
  for (int i = 0; i < 10; ++i) grid_order &= runs[i].value_index[0] == i % 4;
  EXPECT_FALSE(grid_order);
  const std::vector<SweepPoint> again = SweepEnsemble({{"duration", "0.1"}}, parameters, 10);
  for (int i = 0; i < 10; ++i) EXPECT_EQ(again[i].values, runs[i].values);
  EXPECT_THROW(SweepEnsemble({}, parameters, 1), InputError);
}

TEST(SweepGrid, IsTheFullGridFirstParameterSlowest) {
  const std::vector<SweepParameter> parameters = {ParseVary("a.x=1:2:2"), ParseVary("b.y=10:30:3")};
  const std::vector<SweepPoint> grid = SweepGrid({{"duration", "0.1"}}, parameters);
  ASSERT_EQ(grid.size(), 6u);
  const double expect[6][2] = {{1, 10}, {1, 20}, {1, 30}, {2, 10}, {2, 20}, {2, 30}};
  for (int i = 0; i < 6; ++i) {
    EXPECT_EQ(grid[i].index, i);
    EXPECT_EQ(grid[i].values, (std::vector<double>{expect[i][0], expect[i][1]}));
    ASSERT_EQ(grid[i].overrides.size(), 3u);
    EXPECT_EQ(grid[i].overrides[0].Text(), "duration=0.1");  // the fixed ones first
    EXPECT_EQ(grid[i].overrides[1].Text(), "a.x=" + ValueText(expect[i][0]));
    EXPECT_EQ(grid[i].overrides[2].Text(), "b.y=" + ValueText(expect[i][1]));
  }
}

class CheckParameters : public ::testing::Test {
 protected:
  void SetUp() override {
    path_ = (std::filesystem::temp_directory_path() /
             ("sweep_grid_test_" + std::to_string(getpid()) + ".yaml"))
                .string();
    std::ofstream(path_) << R"(name: tiny
duration: 0.01
output_interval: 0.005
materials:
  pp: {diameter: 1.0e-3, linear_density: 7.1e-4, stretch_stiffness: 1178,
       bend_stiffness: 7.36e-5, twist_stiffness: 5.45e-5}
nets:
  - {name: net, material: pp, knots: [3, 3], mesh: 0.1, segments_per_link: 2,
     corner_mass: 0.01, velocity: [0, 0, 0]}
)";
  }
  void TearDown() override { std::filesystem::remove(path_); }
  std::string path_;
};

TEST_F(CheckParameters, KnownPathsPass) {
  EXPECT_NO_THROW(CheckSweepParameters(
      path_, {},
      {ParseVary("materials.pp.bend_stiffness=1e-5:1e-4:3"),
       ParseVary("nets.net.corner_mass=0.01:0.02:2"),
       ParseVary("drag.drag_coefficient=0.8:1.2:3")}));  // a section left at defaults
}

TEST_F(CheckParameters, UnknownPathIsAnErrorNamingTheVary) {
  const std::string error = ErrorOf([&] {
    CheckSweepParameters(path_, {}, {ParseVary("materials.nylon.bend_stiffness=1e-5:1e-4:3")});
  });
  EXPECT_NE(error.find(path_ + ": --vary materials.nylon.bend_stiffness=1e-5:1e-4:3: "
                               "'materials.nylon' is not in the scenario (materials has: pp)"),
            std::string::npos)
      << error;
}

TEST_F(CheckParameters, ListValueOrTwiceVariedIsAnError) {
  EXPECT_NE(ErrorOf([&] {
              CheckSweepParameters(path_, {}, {ParseVary("nets.0.velocity=0:1:2")});
            }).find("expected a list of 3 items as the scenario has there, got a number"),
            std::string::npos);
  EXPECT_NE(ErrorOf([&] {
              CheckSweepParameters(path_, {},
                                   {ParseVary("duration=0.1:0.2:2"), ParseVary("duration=1:2:2")});
            }).find("duration is varied twice"),
            std::string::npos);
}

}  // namespace
}  // namespace netlab::netsim
