#include "libnetsim/characterization/material_file.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "common/yaml_util.h"

namespace netlab::netsim {
namespace {

namespace fs = std::filesystem;

class MaterialFileTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ =
        fs::temp_directory_path() /
        ("material_file_test_" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()) +
         "_" + ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  std::string Write(const std::string& text) {
    const std::string path = (dir_ / "material.yaml").string();
    std::ofstream(path) << text;
    return path;
  }
  // The InputError's message reading `text`, or "" when it reads.
  std::string ErrorOf(const std::string& text) {
    try {
      ReadMaterialFile(Write(text));
    } catch (const InputError& e) {
      return e.what();
    }
    return "";
  }

  fs::path dir_;
};

std::vector<ParameterEstimate> Example() {
  return {{"nylon_1mm", "twist_damping", 1.68e-8, 2.2e-10, "torsion", "bench/torsion.yaml"},
          {"nylon_1mm", "twist_stiffness", 7.07e-5, 3.1e-7, "torsion", "bench/torsion.yaml"},
          {"nylon_1mm", "linear_density", 8.95e-4, 4e-6, "weighing", "torsion: a #1.yaml"},
          {"pp yarn", "bend_stiffness", 7.36e-5, 1e-6, "cantilever", "c.yaml"}};
}

TEST_F(MaterialFileTest, WrittenFileReadsBackTheSameEstimatesInKeyOrder) {
  const std::string path = (dir_ / "out.yaml").string();
  WriteMaterialFile(path, Example(), "netlab characterize: torsion test\nsecond line");
  EXPECT_FALSE(fs::exists(path + ".partial"));
  const std::vector<ParameterEstimate> read = ReadMaterialFile(path);
  ASSERT_EQ(read.size(), 4u);
  // nylon_1mm first (first appearance), its keys in kMaterialKeys' order.
  const std::vector<std::string> keys = {"linear_density", "twist_stiffness", "twist_damping",
                                         "bend_stiffness"};
  for (size_t i = 0; i < read.size(); ++i) EXPECT_EQ(read[i].key, keys[i]);
  for (const ParameterEstimate& want : Example()) {
    bool found = false;
    for (const ParameterEstimate& got : read) {
      if (got.material != want.material || got.key != want.key) continue;
      found = true;
      EXPECT_NEAR(got.value, want.value, 1e-8 * want.value);
      EXPECT_NEAR(got.sigma, want.sigma, 1e-8 * want.sigma);
      EXPECT_EQ(got.test, want.test);
      EXPECT_EQ(got.source, want.source);
    }
    EXPECT_TRUE(found) << want.material << "." << want.key;
  }
}

TEST_F(MaterialFileTest, TheMaterialsBlockIsAScenarioMaterialsBlock) {
  const std::string path = (dir_ / "out.yaml").string();
  WriteMaterialFile(path, Example(), "header");
  const YAML::Node root = YAML::LoadFile(path);
  EXPECT_DOUBLE_EQ(root["materials"]["nylon_1mm"]["twist_stiffness"].as<double>(), 7.07e-5);
  EXPECT_EQ(root["uncertainty"]["pp yarn"]["bend_stiffness"]["test"].as<std::string>(),
            "cantilever");
}

TEST_F(MaterialFileTest, WriterRefusesUnknownKeysTestsAndDuplicates) {
  const std::string path = (dir_ / "out.yaml").string();
  std::vector<ParameterEstimate> bad = Example();
  bad[0].key = "youngs_modulus";
  EXPECT_THROW(WriteMaterialFile(path, bad, ""), std::invalid_argument);
  bad = Example();
  bad[0].test = "guess";
  EXPECT_THROW(WriteMaterialFile(path, bad, ""), std::invalid_argument);
  bad = Example();
  bad.push_back(bad[0]);
  EXPECT_THROW(WriteMaterialFile(path, bad, ""), std::invalid_argument);
  EXPECT_FALSE(fs::exists(path));
}

TEST_F(MaterialFileTest, BrokenFilesAreInputErrorsNamingTheKey) {
  const std::string good_uncertainty =
      "uncertainty:\n  m:\n    bend_stiffness: {sigma: 1e-6, test: cantilever, source: c.yaml}\n";
  struct Case {
    std::string text, fragment;
  };
  const std::vector<Case> cases = {
      {"materials:\n  m: {bend_stiffness: 1e-4}\n", "uncertainty: missing"},
      {"materials:\n  m: {bend_stifness: 1e-4}\n" + good_uncertainty,
       ":2: materials.m.bend_stifness: unknown material key"},
      {"materials:\n  m: {bend_stiffness: .nan}\n" + good_uncertainty,
       "materials.m.bend_stiffness: must be finite"},
      {"materials:\n  m: {bend_stiffness: stiff}\n" + good_uncertainty,
       "materials.m.bend_stiffness: expected a number"},
      {"materials:\n  m: {bend_stiffness: 1e-4, bend_damping: 1e-9}\n" + good_uncertainty,
       "uncertainty.m.bend_damping: missing"},
      {"materials:\n  m: {bend_stiffness: 1e-4}\nuncertainty:\n  m:\n"
       "    bend_stiffness: {sigma: -1, test: cantilever, source: c.yaml}\n",
       ":5: uncertainty.m.bend_stiffness.sigma: must be >= 0"},
      {"materials:\n  m: {bend_stiffness: 1e-4}\nuncertainty:\n  m:\n"
       "    bend_stiffness: {sigma: 1, test: guess, source: c.yaml}\n",
       "uncertainty.m.bend_stiffness.test: unknown test 'guess'"},
      {"materials:\n  m: {bend_stiffness: 1e-4}\nuncertainty:\n  m:\n"
       "    bend_stiffness: {sigma: 1, test: cantilever}\n",
       "uncertainty.m.bend_stiffness.source: missing"},
      {"materials:\n  m: {bend_stiffness: 1e-4}\n" + good_uncertainty +
           "    twist_damping: {sigma: 1, test: torsion, source: t.yaml}\n",
       "uncertainty.m.twist_damping: no such value in materials.m"},
      {"materials:\n  m: {bend_stiffness: 1e-4}\n" + good_uncertainty + "extra: 1\n",
       "extra: unknown key"},
      {"materials: [1, 2]\n" + good_uncertainty, "materials: expected a mapping"},
  };
  for (const Case& c : cases) {
    const std::string error = ErrorOf(c.text);
    EXPECT_NE(error.find(c.fragment), std::string::npos)
        << "want '" << c.fragment << "' in '" << error << "' for:\n"
        << c.text;
    EXPECT_NE(error.find("material.yaml"), std::string::npos) << error;
  }
}

}  // namespace
}  // namespace netlab::netsim
