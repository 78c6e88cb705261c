// `netlab color-net` end to end: the JSON contract, the written coloring.yaml (read back and
// verified independently), a physical palette from candidate colours, and bad input.

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "libreconstruct/coloring/net_coloring.h"
#include "tests/app/cli/run_netlab.h"

namespace {

using netlab::testing::Json;
using netlab::testing::LastJson;
using netlab::testing::RunNetlab;
namespace fs = std::filesystem;
namespace recon = netlab::recon;

class ColorNetCommand : public netlab::testing::CommandTest {
 protected:
  ColorNetCommand() : CommandTest("color_cli") {}
};

TEST_F(ColorNetCommand, ColoursANetAndReportsTheContractFields) {
  for (const char* rule : {"set", "multiset", "cyclic"}) {
    SCOPED_TRACE(rule);
    const std::string out = Path(std::string(rule) + ".yaml");
    const auto r = RunNetlab("color-net --knots 6x6 --rule " + std::string(rule) + " --out " + out +
                             " --json --time-limit 5");
    ASSERT_EQ(r.status, 0) << r.err;
    const Json json = LastJson(r.out);
    for (const char* key : {"colors", "lower_bound", "optimal", "rule", "min_distance", "wall_s"})
      EXPECT_TRUE(json.has(key)) << key;
    EXPECT_EQ(json["rule"].string(), rule);
    EXPECT_EQ(json["min_distance"].number(), 1);
    EXPECT_GE(json["colors"].number(), json["lower_bound"].number());
    const recon::NetColoring coloring = recon::ReadColoring(out);
    EXPECT_EQ(coloring.rows, 6);
    EXPECT_EQ(coloring.cols, 6);
    EXPECT_EQ(coloring.colors, json["colors"].number());
    ASSERT_EQ(static_cast<int>(coloring.link_colour.size()), recon::NumLinks(6, 6));
    std::string why;
    EXPECT_TRUE(recon::VerifyColoring(coloring, &why)) << why;
  }
}

TEST_F(ColorNetCommand, DistanceTwoNeedsNoFewerColours) {
  const auto one = RunNetlab("color-net --knots 5x5 --out " + Path("d1.yaml") + " --json");
  const auto two =
      RunNetlab("color-net --knots 5x5 --distance 2 --out " + Path("d2.yaml") + " --json");
  ASSERT_EQ(one.status, 0) << one.err;
  ASSERT_EQ(two.status, 0) << two.err;
  EXPECT_GE(LastJson(two.out)["colors"].number(), LastJson(one.out)["colors"].number());
  EXPECT_EQ(LastJson(two.out)["min_distance"].number(), 2);
  std::string why;
  EXPECT_TRUE(recon::VerifyColoring(recon::ReadColoring(Path("d2.yaml")), &why)) << why;
}

TEST_F(ColorNetCommand, APaletteFileNamesTheYarnColours) {
  std::ofstream(Path("yarns.csv")) << "name,r,g,b\n"
                                      "red,200,30,30\nblue,30,60,200\ngreen,40,170,60\n"
                                      "yellow,230,210,40\nblack,20,20,20\nwhite,240,240,240\n"
                                      "orange,240,130,20\nviolet,130,50,170\npink,240,150,190\n"
                                      "brown,120,70,30\ncyan,40,190,210\ngrey,128,128,128\n";
  const auto r = RunNetlab("color-net --knots 4x4 --palette " + Path("yarns.csv") + " --out " +
                           Path("c.yaml") + " --json");
  ASSERT_EQ(r.status, 0) << r.err;
  const Json json = LastJson(r.out);
  EXPECT_GT(json["min_delta_e"].number(), 10.0);
  std::vector<std::array<int, 3>> srgb;
  const recon::NetColoring coloring = recon::ReadColoring(Path("c.yaml"), &srgb);
  EXPECT_EQ(static_cast<int>(coloring.palette_names.size()), coloring.colors);
  EXPECT_EQ(static_cast<int>(srgb.size()), coloring.colors);
}

TEST_F(ColorNetCommand, BadInputIsNamed) {
  EXPECT_EQ(RunNetlab("color-net --knots 6 --out " + Path("x.yaml")).status, 2);
  EXPECT_EQ(RunNetlab("color-net --knots 6x6 --rule colours --out " + Path("x.yaml")).status, 2);
  EXPECT_EQ(RunNetlab("color-net --knots 6x6").status, 2);  // no --out
  const auto r =
      RunNetlab("color-net --knots 4x4 --palette " + Path("none.csv") + " --out " + Path("x.yaml"));
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("none.csv"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(Path("x.yaml")));
  EXPECT_EQ(RunNetlab("color-net --help").status, 0);
}

}  // namespace
