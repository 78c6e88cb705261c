#pragma once
// The bad-input suite's table (issue 21): each row is one input a new user could give a command,
// with the exit status it must end in and the fragments its message must hold (the file, the key
// or frame, what was expected). Every row is also checked for what no bad input may do: end in a
// signal or an unexplained std::bad_alloc, or bury netlab's own line under a library's noise
// (OpenCV's, GStreamer's or libpng's lines may only follow it).

#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "tests/app/cli/run_netlab.h"

namespace netlab::testing {

struct BadInput {
  std::string what;                    // the kind of bad input, named in a failure
  std::string args;                    // the netlab arguments; "{dir}" is the fixture folder
  int status;                          // expected exit status: 1 bad input, 2 usage
  std::vector<std::string> fragments;  // each must be in stderr
};

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
  const NetlabResult r = RunNetlab(Substitute(input.args, dir));
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
