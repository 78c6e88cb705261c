#pragma once
// The bad-input suite's table: each row is one input a new user could give a command,
// with the exit status it must end in and the fragments its message must hold (the file, the key
// or frame, what was expected). Every row is also checked for what no bad input may do: end in a
// signal or an unexplained std::bad_alloc, or bury netlab's own line under a library's noise
// (OpenCV's, GStreamer's or libpng's lines may only follow it); and a row may name files the run
// must leave as they were (an output never replaces an input, a failed run leaves every
// existing output unchanged).

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "tests/app/cli/run_netlab.h"
#include "tests/file_size_limit.h"

namespace netlab::testing {

struct BadInput {
  std::string what;                    // the kind of bad input, named in a failure
  std::string args;                    // the netlab arguments; "{dir}" is the fixture folder
  int status;                          // expected exit status: 1 bad input, 2 usage
  std::vector<std::string> fragments;  // each must be in stderr
  // Files ("{dir}/...") the run must leave as they were: an input it must not replace, an output
  // a failed run must not touch. A regular file byte for byte; a FIFO, device or folder stays
  // one (and is not read); a missing file stays missing.
  std::vector<std::string> unchanged = {};
  // When > 0, the run may write no file past this many bytes (RLIMIT_FSIZE, SIGXFSZ ignored: a
  // write past it fails with EFBIG as a write to a full disk fails with ENOSPC), and no
  // "<unchanged>.partial" may be left behind.
  long file_limit = 0;
};

// What ExpectBadInput compares of an `unchanged` file: its kind and, for a regular file, its bytes.
inline std::string Snapshot(const std::string& path) {
  namespace fs = std::filesystem;
  std::error_code error;
  const fs::file_status link = fs::symlink_status(path, error);
  if (!fs::exists(link)) return "(missing)";
  std::string kind =
      fs::is_symlink(link) ? "link to " + fs::read_symlink(path, error).string() + ": " : "";
  const fs::file_status status = fs::status(path, error);
  if (!fs::is_regular_file(status))
    return kind + "(not a regular file, type " + std::to_string(static_cast<int>(status.type())) +
           ")";
  std::ifstream in(path, std::ios::binary);
  std::ostringstream bytes;
  bytes << in.rdbuf();
  return kind + bytes.str();
}

inline std::string Substitute(std::string text, const std::string& dir) {
  for (size_t at = text.find("{dir}"); at != std::string::npos; at = text.find("{dir}", at))
    text.replace(at, 5, dir), at += dir.size();
  return text;
}

// Where netlab's own message starts in stderr: the first line that starts with "netlab ".
inline size_t OwnLine(const std::string& err) {
  if (err.rfind("netlab ", 0) == 0) return 0;
  const size_t at = err.find("\nnetlab ");
  return at == std::string::npos ? std::string::npos : at + 1;
}

inline void ExpectBadInput(const BadInput& input, const std::string& dir) {
  SCOPED_TRACE(input.what + ": netlab " + Substitute(input.args, dir));
  std::vector<std::string> before;
  for (const std::string& file : input.unchanged) before.push_back(Snapshot(Substitute(file, dir)));
  std::optional<FileSizeLimit> limit;
  if (input.file_limit > 0) limit.emplace(input.file_limit);
  const NetlabResult r = RunNetlab(Substitute(input.args, dir));
  limit.reset();
  if (input.file_limit > 0) {
    for (const std::string& file : input.unchanged) {
      EXPECT_FALSE(std::filesystem::exists(Substitute(file, dir) + ".partial"))
          << Substitute(file, dir) << ".partial was left behind";
    }
  }
  for (size_t i = 0; i < input.unchanged.size(); ++i)
    EXPECT_TRUE(Snapshot(Substitute(input.unchanged[i], dir)) == before[i])
        << Substitute(input.unchanged[i], dir) << " was changed by the run";
  EXPECT_EQ(r.status, input.status) << r.err;
  for (const std::string& fragment : input.fragments)
    EXPECT_NE(r.err.find(Substitute(fragment, dir)), std::string::npos)
        << "missing '" << Substitute(fragment, dir) << "' in:\n"
        << r.err;
  EXPECT_EQ(r.err.find("std::bad_alloc"), std::string::npos) << r.err;
  const size_t own = OwnLine(r.err);
  EXPECT_NE(own, std::string::npos) << "no line of netlab's own:\n" << r.err;
  for (const char* noise : {"[ WARN", "[ERROR", "OpenCV(", "GStreamer", "libpng"}) {
    const size_t at = r.err.find(noise);
    EXPECT_TRUE(at == std::string::npos || at > own)
        << "'" << noise << "' comes before netlab's own line:\n"
        << r.err;
  }
}

inline void ExpectBadInputs(const std::vector<BadInput>& inputs, const std::string& dir) {
  for (const BadInput& input : inputs) ExpectBadInput(input, dir);
}

}  // namespace netlab::testing
