#pragma once
// Scratch folders and hand-written image files for the libreconstruct tests.

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <functional>
#include <initializer_list>
#include <opencv2/core.hpp>
#include <string>

#include "common/errors.h"

namespace netlab::recon::testing {

// A folder of its own per process and test (ctest runs the test cases in parallel), removed at
// the end.
class ScratchDir {
 public:
  explicit ScratchDir(const std::string& tag) {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    std::string name = info ? info->name() : "global";
    std::replace(name.begin(), name.end(), '/', '_');  // parameterised tests: "Name/param"
    path_ = std::filesystem::temp_directory_path() /
            ("netlab_recon_" + tag + "_" + std::to_string(getpid()) + "_" + name);
    std::filesystem::remove_all(path_);
    std::filesystem::create_directories(path_);
  }
  ~ScratchDir() {
    std::error_code ignored;
    std::filesystem::remove_all(path_, ignored);
  }
  ScratchDir(const ScratchDir&) = delete;
  ScratchDir& operator=(const ScratchDir&) = delete;

  const std::filesystem::path& path() const { return path_; }
  std::string operator/(const std::string& name) const { return (path_ / name).string(); }

 private:
  std::filesystem::path path_;
};

inline void WriteBytes(const std::string& path, const std::string& bytes) {
  std::filesystem::create_directories(std::filesystem::path(path).parent_path());
  std::ofstream out(path, std::ios::binary);
  out << bytes;
  ASSERT_TRUE(out.good()) << path;
}

// A binary PGM (P5) written by hand: 8 bit (maxval 255) or 16 bit big-endian (maxval 65535).
inline std::string PgmBytes(const cv::Mat& image) {
  const bool wide = image.depth() == CV_16U;
  std::string bytes = "P5\n# netlab test\n" + std::to_string(image.cols) + " " +
                      std::to_string(image.rows) + "\n" + (wide ? "65535" : "255") + "\n";
  for (int y = 0; y < image.rows; ++y)
    for (int x = 0; x < image.cols; ++x) {
      if (wide) {
        const uint16_t v = image.at<uint16_t>(y, x);
        bytes.push_back(static_cast<char>(v >> 8));
        bytes.push_back(static_cast<char>(v & 0xFF));
      } else {
        bytes.push_back(static_cast<char>(image.at<uint8_t>(y, x)));
      }
    }
  return bytes;
}

inline void WritePgm(const std::string& path, const cv::Mat& image) {
  WriteBytes(path, PgmBytes(image));
}

// Exactly equal size, type and pixels.
inline ::testing::AssertionResult SameImage(const cv::Mat& a, const cv::Mat& b) {
  if (a.size() != b.size() || a.type() != b.type())
    return ::testing::AssertionFailure()
           << "size/type " << a.cols << "x" << a.rows << " type " << a.type() << " vs " << b.cols
           << "x" << b.rows << " type " << b.type();
  if (a.empty()) return ::testing::AssertionSuccess();
  const double diff = cv::norm(a, b, cv::NORM_INF);
  if (diff != 0.0) return ::testing::AssertionFailure() << "pixels differ by up to " << diff;
  return ::testing::AssertionSuccess();
}

// The message of the InputError that `read` throws ("" when it throws none).
inline std::string ErrorOf(const std::function<void()>& read) {
  try {
    read();
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

// Success when `message` is an error that mentions every one of `parts`.
inline ::testing::AssertionResult Mentions(const std::string& message,
                                           std::initializer_list<std::string> parts) {
  if (message.empty()) return ::testing::AssertionFailure() << "no error";
  for (const std::string& part : parts)
    if (message.find(part) == std::string::npos)
      return ::testing::AssertionFailure()
             << "'" << message << "' does not mention '" << part << "'";
  return ::testing::AssertionSuccess();
}

}  // namespace netlab::recon::testing
