// The bad-input suite of `netlab characterize` (tests/app/cli/bad_input.h): each row one
// kind of broken bench-test file, the exit status and what its message must name (the file, the
// line where there is one, the key). The fixtures are written at run time from a good torsion test.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <utility>
#include <vector>

#include "tests/app/cli/bad_input.h"

namespace netlab::testing {
namespace {

// A torsion test of 30 samples of a 10 Hz oscillation; rows "  - [t, angle]" from line 7 on.
std::string Torsion(bool oscillating = true) {
  std::string text =
      "test: torsion\nmaterial: nylon_1mm\nlength: 0.18\ninertia: 5.0e-8\n"
      "weighing: {mass: 8.95e-4, mass_sigma: 1.0e-6, length: 1.0, length_sigma: 1.0e-3}\n"
      "samples:\n";
  for (int i = 0; i < 30; ++i) {
    const double t = 0.01 * i, angle = oscillating ? 0.5 * std::cos(2 * M_PI * 10 * t) : 0.5;
    text += "  - [" + std::to_string(t) + ", " + std::to_string(angle) + "]\n";
  }
  return text;
}

std::string Tensile(bool moving, double force_scale = 1.0) {
  std::string text = "test: tensile\nmaterial: m\ngauge_length: 0.1\nsamples:\n";
  char force[32];
  for (int i = 0; i < 20; ++i) {
    std::snprintf(force, sizeof(force), "%g", 0.1 * i * force_scale);
    text += "  - [" + std::to_string(0.01 * i) + ", " + (moving ? std::to_string(1e-5 * i) : "0") +
            ", " + force + "]\n";
  }
  return text;
}

// A cantilever test of a 0.5 m thread whose shape is `points` [x, y]; rows from line 6 on.
std::string Cantilever(const std::vector<std::pair<double, double>>& points) {
  std::string text =
      "test: cantilever\nmaterial: m\nlength: 0.5\n"
      "weighing: {mass: 1e-3, mass_sigma: 1e-6, length: 1, length_sigma: 1e-3}\n"
      "shape:\n";
  for (const auto& [x, y] : points)
    text += "  - [" + std::to_string(x) + ", " + std::to_string(y) + "]\n";
  return text;
}

class BadInputCharacterize : public CommandTest {
 protected:
  BadInputCharacterize() : CommandTest("bad_input_characterize") {}
  void SetUp() override {
    CommandTest::SetUp();
    Write("good.yaml", Torsion());
    Write("empty.yaml", "");
    Write("not_yaml.yaml", "test: [torsion\n  - {");
    Write("unknown_key.yaml", Replace(Torsion(), "inertia: 5.0e-8", "inertia: 5.0e-8\ninertai: 1"));
    Write("missing_key.yaml", Replace(Torsion(), "inertia: 5.0e-8\n", ""));
    Write("wrong_kind.yaml", Replace(Torsion(), "length: 0.18", "length: long"));
    Write("nan.yaml", Replace(Torsion(), "inertia: 5.0e-8", "inertia: .nan"));
    Write("negative_length.yaml", Replace(Torsion(), "length: 0.18", "length: -0.18"));
    Write("negative_mass.yaml", Replace(Torsion(), "mass: 8.95e-4", "mass: -8.95e-4"));
    Write("time_back.yaml", Replace(Torsion(), "[0.020000,", "[0.001000,"));
    Write("short_row.yaml", Replace(Torsion(), "[0.020000, ", "[0.020000"));
    Write("text_cell.yaml", Replace(Torsion(), "[0.020000, ", "[0.020000, abc, "));
    Write("few_points.yaml", Torsion().substr(0, Torsion().find("  - [0.050000")));
    Write("flat.yaml", Torsion(false));
    Write("unknown_test.yaml", Replace(Torsion(), "test: torsion", "test: bending"));
    Write("tensile_static.yaml", Tensile(false));
    Write("tensile_huge.yaml", Tensile(true, 1e300));
    Write("cantilever_unweighed.yaml",
          "test: cantilever\nmaterial: m\nlength: 0.5\ntip_deflection: {vertical: 0.1, sigma: "
          "1e-3}\n");
    Write("cantilever_too_deep.yaml",
          "test: cantilever\nmaterial: m\nlength: 0.5\n"
          "weighing: {mass: 1e-3, mass_sigma: 1e-6, length: 1, length_sigma: 1e-3}\n"
          "tip_deflection: {vertical: 0.6, sigma: 1e-3}\n");
    // A shape no thread clamped horizontally takes: rising above the clamp (y measured down),
    // running back towards it (x measured towards the clamp), folding back half way.
    Write("cantilever_up.yaml", Cantilever({{0.1, 0.02}, {0.2, 0.06}, {0.3, 0.12}}));
    Write("cantilever_back.yaml", Cantilever({{-0.1, -0.01}, {-0.2, -0.04}, {-0.3, -0.09}}));
    Write("cantilever_folded.yaml",
          Cantilever({{0.1, -0.01}, {0.2, -0.04}, {0.15, -0.09}, {0.1, -0.15}}));
    Write("no_material.yaml", Replace(Torsion(), "material: nylon_1mm\n", ""));
    // What a YAML reader takes without a word and netlab would misread.
    Write("twice.yaml",
          Replace(Torsion(), "material: nylon_1mm\n", "material: nylon_1mm\ntest: tensile\n"));
    Write("tagged.yaml", Replace(Torsion(), "length: 0.18", "length: !!str 0.18"));
    Write("two_documents.yaml", Torsion() + "---\ntest: tensile\n");
    std::filesystem::create_directory(Path("folder.yaml"));
  }
  void Write(const std::string& name, const std::string& text) {
    std::ofstream(Path(name)) << text;
  }
  static std::string Replace(std::string text, const std::string& from, const std::string& to) {
    text.replace(text.find(from), from.size(), to);
    return text;
  }
};

TEST_F(BadInputCharacterize, EachKindEndsInAClearError) {
  const std::string out = " --out {dir}/material.yaml";
  ExpectBadInputs(
      {
          {"no test file", "characterize --out {dir}/m.yaml", 2, {"expected one TEST.yaml"}},
          {"no --out", "characterize {dir}/good.yaml", 2, {"--out"}},
          {"--out is the test file",
           "characterize {dir}/good.yaml --out {dir}/good.yaml",
           1,
           {"--out {dir}/good.yaml", "the test file {dir}/good.yaml"},
           {"{dir}/good.yaml"}},
          {"missing file",
           "characterize {dir}/missing.yaml" + out,
           1,
           {"{dir}/missing.yaml", "cannot open"}},
          {"empty file", "characterize {dir}/empty.yaml" + out, 1, {"{dir}/empty.yaml", "empty"}},
          {"not YAML", "characterize {dir}/not_yaml.yaml" + out, 1, {"{dir}/not_yaml.yaml:"}},
          {"extra key",
           "characterize {dir}/unknown_key.yaml" + out,
           1,
           {"{dir}/unknown_key.yaml:5: inertai: unknown key"}},
          {"missing key",
           "characterize {dir}/missing_key.yaml" + out,
           1,
           {"{dir}/missing_key.yaml:", "inertia: missing"}},
          {"no material",
           "characterize {dir}/no_material.yaml" + out,
           1,
           {"{dir}/no_material.yaml:", "material: missing"}},
          {"wrong kind",
           "characterize {dir}/wrong_kind.yaml" + out,
           1,
           {"{dir}/wrong_kind.yaml:3: length: expected a number"}},
          {"NaN",
           "characterize {dir}/nan.yaml" + out,
           1,
           {"{dir}/nan.yaml:4: inertia: must be finite"}},
          {"negative length",
           "characterize {dir}/negative_length.yaml" + out,
           1,
           {"{dir}/negative_length.yaml:3: length: must be > 0"}},
          {"negative mass",
           "characterize {dir}/negative_mass.yaml" + out,
           1,
           {"{dir}/negative_mass.yaml:5: weighing.mass: must be > 0"}},
          {"time going back",
           "characterize {dir}/time_back.yaml" + out,
           1,
           {"{dir}/time_back.yaml:9: samples[2]: time 0.001", "does not increase"}},
          {"short row",
           "characterize {dir}/short_row.yaml" + out,
           1,
           {"{dir}/short_row.yaml:9: samples[2]: expected a row of 2 numbers"}},
          {"text in a row",
           "characterize {dir}/text_cell.yaml" + out,
           1,
           {"{dir}/text_cell.yaml:9: samples[2]:"}},
          {"too few points",
           "characterize {dir}/few_points.yaml" + out,
           1,
           {"{dir}/few_points.yaml:", "samples: too few points: 5"}},
          {"no oscillation",
           "characterize {dir}/flat.yaml" + out,
           1,
           {"{dir}/flat.yaml:", "samples: cannot be fitted", "no oscillation"}},
          {"unknown test",
           "characterize {dir}/unknown_test.yaml" + out,
           1,
           {"{dir}/unknown_test.yaml:1: test: expected tensile, cantilever or torsion"}},
          {"tensile without a cycle",
           "characterize {dir}/tensile_static.yaml" + out,
           1,
           {"{dir}/tensile_static.yaml:", "samples: cannot be fitted"}},
          {"cantilever without weighing",
           "characterize {dir}/cantilever_unweighed.yaml" + out,
           1,
           {"{dir}/cantilever_unweighed.yaml:", "weighing: missing"}},
          {"tip below the length",
           "characterize {dir}/cantilever_too_deep.yaml" + out,
           1,
           {"{dir}/cantilever_too_deep.yaml:5: tip_deflection.vertical: must be below"}},
          {"a cantilever bending upward",
           "characterize {dir}/cantilever_up.yaml" + out,
           1,
           {"{dir}/cantilever_up.yaml:6: shape[0]: y 0.02 m is above the clamp", "y is up"}},
          {"a cantilever running back from the clamp",
           "characterize {dir}/cantilever_back.yaml" + out,
           1,
           {"{dir}/cantilever_back.yaml:6: shape[0]: x -0.1 m is behind the clamp",
            "from the clamp to the tip"}},
          {"a cantilever folding back towards the clamp",
           "characterize {dir}/cantilever_folded.yaml" + out,
           1,
           {"{dir}/cantilever_folded.yaml:8: shape[2]: x 0.15 m runs back towards the clamp "
            "(x 0.2 m before it)"}},
          {"forces of 1e300 N",
           "characterize {dir}/tensile_huge.yaml" + out,
           1,
           {"{dir}/tensile_huge.yaml", "cannot be fitted"}},
          {"a key given twice",
           "characterize {dir}/twice.yaml" + out,
           1,
           {"{dir}/twice.yaml:3: test: given twice, at lines 1 and 3"}},
          {"a tag on a number",
           "characterize {dir}/tagged.yaml" + out,
           1,
           {"{dir}/tagged.yaml:3: length: the tag '!!str'"}},
          {"a second document",
           "characterize {dir}/two_documents.yaml" + out,
           1,
           {"{dir}/two_documents.yaml:38: a second YAML document"}},
          {"a folder as the test file",
           "characterize {dir}/folder.yaml" + out,
           1,
           {"{dir}/folder.yaml: is a folder"}},
      },
      dir_.string());
  // No bad input leaves an output behind.
  EXPECT_FALSE(std::filesystem::exists(Path("material.yaml")));
  EXPECT_FALSE(std::filesystem::exists(Path("material.yaml.partial")));
}

// A disk that fills while the material file is written (a file-size limit of 400 bytes, below
// the file's 522 and above the message's, stands in for it): exit 1 naming the file, the previous
// file byte for byte, no partial file beside it.
TEST_F(BadInputCharacterize, AFullDiskLeavesThePreviousMaterialFile) {
  Write("previous.yaml", "the previous material file");
  ExpectBadInput({"characterize onto a full disk",
                  "characterize {dir}/good.yaml --out "
                  "{dir}/previous.yaml",
                  1,
                  {"{dir}/previous.yaml: cannot write"},
                  {"{dir}/previous.yaml"},
                  400},
                 dir_.string());
}

}  // namespace
}  // namespace netlab::testing
