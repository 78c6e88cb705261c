#pragma once
// Runs the `netlab` executable as a user does (NETLAB_EXE, set by tests/app/CMakeLists.txt) and
// captures its exit status, stdout and stderr; LastJson parses the --json summary strictly.

#include <gtest/gtest.h>
#include <unistd.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "tests/app/cli/json_parse.h"

namespace netlab::testing {

struct NetlabResult {
  int status;
  std::string out;  // stdout
  std::string err;  // stderr
};

inline NetlabResult RunNetlab(const std::string& args) {
  static int calls = 0;
  const auto err_path =
      std::filesystem::temp_directory_path() /
      ("netlab_cli_stderr_" + std::to_string(getpid()) + "_" + std::to_string(calls++) + ".txt");
  const std::string command = std::string(NETLAB_EXE) + " " + args + " 2>" + err_path.string();
  FILE* pipe = popen(command.c_str(), "r");
  std::string out;
  std::array<char, 4096> buffer;
  size_t n;
  while ((n = fread(buffer.data(), 1, buffer.size(), pipe)) > 0) out.append(buffer.data(), n);
  const int status = WEXITSTATUS(pclose(pipe));
  std::stringstream err;
  err << std::ifstream(err_path).rdbuf();
  std::filesystem::remove(err_path);
  return {status, out, err.str()};
}

// The JSON summary: the last line of stdout, parsed strictly.
inline Json LastJson(const std::string& out) {
  std::string text = out;
  while (!text.empty() && text.back() == '\n') text.pop_back();
  return JsonParser::Parse(text.substr(text.rfind('\n') + 1));
}

// A fixture with a scratch folder of its own per process and test (ctest runs tests in
// parallel), removed afterwards; Path(name) is a file in it.
class CommandTest : public ::testing::Test {
 protected:
  explicit CommandTest(const std::string& tag) : tag_(tag) {}
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() /
           ("netlab_" + tag_ + "_" + std::to_string(getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    std::filesystem::remove_all(dir_);
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  std::string Path(const std::string& name) const { return (dir_ / name).string(); }

  std::string tag_;
  std::filesystem::path dir_;
};

}  // namespace netlab::testing
