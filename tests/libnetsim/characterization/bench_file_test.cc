#include "libnetsim/characterization/bench_file.h"

#include <gtest/gtest.h>

#include <string>

#include "common/yaml_util.h"

namespace netlab::netsim {
namespace {

std::string Torsion(int samples) {
  std::string text =
      "test: torsion\nmaterial: nylon_1mm\nlength: 0.18\ninertia: 5.0e-8\n"
      "weighing: {mass: 8.95e-4, mass_sigma: 1.0e-6, length: 1.0, length_sigma: 1.0e-3}\n"
      "samples:\n";
  for (int i = 0; i < samples; ++i)
    text += "  - [" + std::to_string(0.01 * i) + ", " + std::to_string(0.1 * (i % 3)) + "]\n";
  return text;
}

std::string ErrorOf(const std::string& text) {
  try {
    ParseBenchTest(text, "t.yaml");
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(BenchTest, TorsionFileReads) {
  const BenchTest test = ParseBenchTest(Torsion(30), "dir/t.yaml");
  EXPECT_EQ(test.kind, BenchKind::kTorsion);
  EXPECT_EQ(test.material, "nylon_1mm");
  EXPECT_EQ(test.source, "t.yaml");
  EXPECT_DOUBLE_EQ(test.torsion.inertia, 5e-8);
  ASSERT_EQ(test.torsion.samples.size(), 30);
  EXPECT_DOUBLE_EQ(test.torsion.samples.rows[4][1], 0.1);
  ASSERT_TRUE(test.weighing);
  EXPECT_NEAR(test.weighing->LinearDensity(), 8.95e-4, 1e-12);
  EXPECT_NEAR(test.weighing->LinearDensitySigma(), 8.95e-4 * std::hypot(1e-6 / 8.95e-4, 1e-3),
              1e-15);
}

TEST(BenchTest, WrittenTextReadsBackTheSameTest) {
  const BenchTest test = ParseBenchTest(Torsion(25), "t.yaml");
  const BenchTest back = ParseBenchTest(BenchTestText(test, "a comment\nsecond"), "t.yaml");
  EXPECT_EQ(back.kind, test.kind);
  EXPECT_EQ(back.torsion.samples.rows, test.torsion.samples.rows);
  EXPECT_DOUBLE_EQ(back.torsion.length, test.torsion.length);
  EXPECT_DOUBLE_EQ(back.weighing->mass_sigma, test.weighing->mass_sigma);
}

TEST(BenchTest, BadSeriesAreNamedWithTheirLine) {
  std::string text = Torsion(30);
  text.replace(text.find("[0.030000,"), 10, "[0.005000,");
  EXPECT_NE(ErrorOf(text).find("t.yaml:10: samples[3]: time 0.005"), std::string::npos)
      << ErrorOf(text);
  EXPECT_NE(ErrorOf(Torsion(5)).find("samples: too few points: 5"), std::string::npos);
  text = Torsion(30);
  text.replace(text.find("[0.030000, 0.000000]"), 20, "[0.03, .nan]");
  EXPECT_NE(ErrorOf(text).find("samples[3]: must be finite"), std::string::npos) << ErrorOf(text);
}

TEST(BenchTest, CantileverNeedsWeighingAndOneOfShapeOrTipDeflection) {
  const std::string base = "test: cantilever\nmaterial: m\nlength: 0.5\n";
  EXPECT_NE(ErrorOf(base + "tip_deflection: {vertical: 0.1, sigma: 1e-3}\n").find("weighing"),
            std::string::npos);
  EXPECT_NE(ErrorOf(base).find("shape: give either"), std::string::npos) << ErrorOf(base);
}

}  // namespace
}  // namespace netlab::netsim
