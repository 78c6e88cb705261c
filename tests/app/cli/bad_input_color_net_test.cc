// `netlab color-net` under bad input: each row is one kind of mistake a user can make,
// with the exit status and the words the message must hold. Nothing here may end in a signal or
// an unexplained std::bad_alloc (checked by ExpectBadInputs on every row).

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "tests/app/cli/bad_input.h"

namespace {

using netlab::testing::BadInput;

class BadInputColorNet : public netlab::testing::CommandTest {
 protected:
  BadInputColorNet() : CommandTest("bad_color_net") {}
};

TEST_F(BadInputColorNet, EveryKindEndsInANamedError) {
  std::ofstream(Path("two.csv")) << "name,r,g,b\nred,200,30,30\nblue,30,60,200\n";
  const std::string out = " --out {dir}/c.yaml";
  const std::vector<BadInput> rows = {
      {"--knots without an x",
       "color-net --knots 6" + out,
       2,
       {"--knots expects ROWSxCOLS", "'6'"}},
      {"--knots with junk after it", "color-net --knots 6x6x" + out, 2, {"--knots", "'6x6x'"}},
      {"--knots with letters", "color-net --knots axb" + out, 2, {"--knots", "'axb'"}},
      {"--knots below 2 per side", "color-net --knots 1x6" + out, 2, {"--knots 1x6", "2..1000"}},
      {"--knots above 1000 per side", "color-net --knots 1001x10" + out, 2, {"2..1000"}},
      {"--knots negative", "color-net --knots -3x5" + out, 2, {"2..1000"}},
      {"no --knots", "color-net" + out, 2, {"--knots"}},
      {"no --out", "color-net --knots 6x6", 2, {"--out"}},
      {"an unknown --rule",
       "color-net --knots 6x6 --rule colours" + out,
       2,
       {"--rule expects set, multiset or cyclic", "'colours'"}},
      {"--distance 0", "color-net --knots 6x6 --distance 0" + out, 2, {"--distance", "1..4"}},
      {"--distance 5", "color-net --knots 6x6 --distance 5" + out, 2, {"--distance", "1..4"}},
      {"--distance not a number",
       "color-net --knots 6x6 --distance two" + out,
       2,
       {"--distance", "'two'"}},
      {"--radius negative", "color-net --knots 6x6 --radius -1" + out, 2, {"--radius"}},
      {"--time-limit negative", "color-net --knots 6x6 --time-limit -1" + out, 2, {"--time-limit"}},
      {"--time-limit not a number",
       "color-net --knots 6x6 --time-limit nan" + out,
       2,
       {"--time-limit"}},
      {"an unknown --background",
       "color-net --knots 6x6 --background grey" + out,
       2,
       {"--background expects black, white or none", "'grey'"}},
      {"an unknown option", "color-net --knots 6x6 --colours 5" + out, 2, {"colours"}},
      {"a stray argument", "color-net extra --knots 6x6" + out, 2, {"unexpected argument 'extra'"}},
      {"a missing --palette file",
       "color-net --knots 4x4 --palette {dir}/none.csv" + out,
       1,
       {"{dir}/none.csv"}},
      {"a --palette with fewer dyes than colours",
       "color-net --knots 6x6 --palette {dir}/two.csv" + out,
       1,
       {"{dir}/two.csv", "2 candidate colours", "needs 5"}},
      {"--out is the --palette file",
       "color-net --knots 4x4 --palette {dir}/two.csv --out {dir}/two.csv",
       1,
       {"--out {dir}/two.csv", "the --palette file {dir}/two.csv"},
       {"{dir}/two.csv"}},
      {"--out in a folder that does not exist",
       "color-net --knots 4x4 --out {dir}/no/such/c.yaml",
       1,
       {"{dir}/no/such/c.yaml"}},
      // More knots than 64 colours can tell apart: refused from the lower bound, before any
      // search (this took all memory and was killed).
      {"a net no 64-colour palette can identify",
       "color-net --knots 1000x1000" + out,
       1,
       {"--knots 1000x1000", "no palette of at most 64 colours", "lower bound 65"}},
      {"--distance 2 where two corners are neighbours",
       "color-net --knots 2x5 --distance 2" + out,
       1,
       {"--knots 2x5", "no palette"}},
      // Partner lists of ~2 R^2 knots for each of 10^6 knots: terabytes, on any machine.
      {"a radius whose search cannot fit in memory",
       "color-net --knots 1000x1000 --radius 999" + out,
       1,
       {"--knots 1000x1000 --radius 999", "the colouring search needs ~", "TB", "available"}},
      {"a full disk (the colouring of 11 x 11 knots is ~9 KiB, the limit 1 KiB)",
       "color-net --knots 11x11 --out {dir}/previous.yaml --quiet",
       1,
       {"{dir}/previous.yaml: cannot write {dir}/previous.yaml.partial"},
       {"{dir}/previous.yaml"},
       1024},
  };
  std::ofstream(Path("previous.yaml")) << "the previous colouring";
  netlab::testing::ExpectBadInputs(rows, dir_.string());
  EXPECT_FALSE(std::filesystem::exists(Path("c.yaml")));
}

}  // namespace
