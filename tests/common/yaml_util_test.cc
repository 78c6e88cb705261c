// common/yaml_util.h: what a YAML reader accepts but netlab would misread is refused with the
// file and line named: a key given twice (both lines), a tag on a value, a second document, an
// alias bomb, a folder or a device given as the file; a value too long to quote is shortened.

#include "common/yaml_util.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

namespace netlab {
namespace {

// The message LoadYamlString gives for `text`, "" when it loads.
std::string Refusal(const std::string& text) {
  try {
    LoadYamlString(text, "f.yaml");
    return "";
  } catch (const InputError& e) {
    return e.what();
  }
}

TEST(LoadYaml, AKeyGivenTwiceIsRefusedNamingBothLines) {
  EXPECT_EQ(Refusal("duration: 0.5\nname: a\nduration: -3\n"),
            "f.yaml:3: duration: given twice, at lines 1 and 3 (a YAML reader keeps one of "
            "them silently); keep one");
  // In a nested mapping and in a list's mapping, by its dotted path.
  EXPECT_NE(Refusal("materials:\n  nylon:\n    a: 1\n    a: 2\n")
                .find("f.yaml:4: materials.nylon.a: given twice, at lines 3 and 4"),
            std::string::npos);
  EXPECT_NE(Refusal("nets:\n  - knots: 1\n    knots: 2\n")
                .find("f.yaml:3: nets[0].knots: given "
                      "twice"),
            std::string::npos);
  EXPECT_NE(Refusal("materials: {}\nmaterials: {}\n").find("materials: given twice"),
            std::string::npos);
  // The same key in two mappings is no duplicate.
  EXPECT_EQ(Refusal("a: {x: 1}\nb: {x: 1}\n"), "");
}

TEST(LoadYaml, ATagOnAValueIsRefused) {
  EXPECT_EQ(Refusal("duration: !!str 5\n"),
            "f.yaml:1: duration: the tag '!!str' is not read by netlab (the value would be read "
            "as if it had none); remove it");
  EXPECT_NE(Refusal("a:\n  b: !seconds 3\n").find("f.yaml:2: a.b: the tag '!seconds'"),
            std::string::npos);
  EXPECT_NE(Refusal("a: !!map {b: 1}\n").find("the tag '!!map'"), std::string::npos);
  // Quoted and plain values carry no tag.
  EXPECT_EQ(Refusal("a: \"5\"\nb: '5'\nc: 5\nd:\ne: ~\n"), "");
}

TEST(LoadYaml, ASecondDocumentIsRefused) {
  EXPECT_EQ(Refusal("a: 1\n---\nb: 2\n"),
            "f.yaml:3: a second YAML document (after a '---' line): netlab reads one document "
            "per file, and would ignore this one; remove it or the '---'");
  // A document start before the only document, an end marker, or an empty second document hold
  // nothing that would be ignored.
  EXPECT_EQ(Refusal("---\na: 1\n"), "");
  EXPECT_EQ(Refusal("a: 1\n...\n"), "");
  EXPECT_EQ(Refusal("a: 1\n---\n"), "");
  EXPECT_TRUE(LoadYamlString("", "f.yaml").IsNull());
}

TEST(LoadYaml, AnAliasBombIsRefusedBeforeItIsExpanded) {
  std::string text = "a: &a [1, 1, 1, 1, 1, 1, 1, 1, 1]\n";
  for (char c = 'b'; c <= 'j'; ++c) {  // 9^10 = 3.5e9 values once expanded
    text += std::string(1, c) + ": &" + c + " [";
    for (int i = 0; i < 9; ++i) text += std::string(i ? ", " : "") + "*" + static_cast<char>(c - 1);
    text += "]\n";
  }
  const auto start = std::chrono::steady_clock::now();
  EXPECT_NE(Refusal(text).find("f.yaml: its aliases ('*name') expand to more values than the "
                               "file's text holds"),
            std::string::npos);
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), 5.0);
  // An alias used as YAML means it is read.
  EXPECT_EQ(Refusal("nylon: &nylon {a: 1}\nyarn: *nylon\n"), "");
}

TEST(LoadYaml, AFolderADeviceOrAMissingFileIsNamed) {
  const std::string dir = ::testing::TempDir() + "yaml_util_" + std::to_string(getpid());
  std::filesystem::create_directories(dir);
  auto message = [](const std::string& path) {
    try {
      LoadYamlFile(path);
      return std::string();
    } catch (const InputError& e) {
      return std::string(e.what());
    }
  };
  EXPECT_EQ(message(dir), dir + ": is a folder, not a YAML file");
  EXPECT_EQ(message(dir + "/missing.yaml"), dir + "/missing.yaml: cannot open file");
  EXPECT_EQ(message("/dev/zero"),
            "/dev/zero: more than 64 MiB; not a YAML file netlab reads (a "
            "device?)");
  std::ofstream(dir + "/twice.yaml") << "a: 1\na: 2\n";
  EXPECT_EQ(message(dir + "/twice.yaml").rfind(dir + "/twice.yaml:2: a: given twice", 0), 0u);
  std::filesystem::remove_all(dir);
}

TEST(YamlMap, AValueTooLongToQuoteIsShortened) {
  const std::string digits(100000, '7');
  try {
    YamlMap(LoadYamlString("a: 1" + digits + "x\n", "f.yaml"), "f.yaml", "").Double("a");
    ADD_FAILURE() << "not refused";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_LT(what.size(), 200u);
    EXPECT_NE(what.find("f.yaml:1: a: expected a number, got '17777"), std::string::npos) << what;
    EXPECT_NE(what.find("(100002 characters)"), std::string::npos) << what;
  }
}

}  // namespace
}  // namespace netlab
