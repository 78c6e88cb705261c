#pragma once
// The one logging header of netlab. Libraries never print to stdout: they log progress and
// warnings here (stderr), and return their results and summaries as values.
//
//   NETLAB_LOG(kInfo) << "read " << n << " frames";
//
// The threshold is process-wide (SetLogLevel); messages are written whole, one line each, so
// lines from worker threads never interleave.

#include <atomic>
#include <cstdio>
#include <mutex>
#include <sstream>
#include <string>

namespace netlab {

enum class LogLevel { kDebug = 0, kInfo = 1, kWarning = 2, kError = 3, kQuiet = 4 };

inline std::atomic<int>& LogThreshold() {
  static std::atomic<int> threshold{static_cast<int>(LogLevel::kInfo)};
  return threshold;
}

inline void SetLogLevel(LogLevel level) { LogThreshold() = static_cast<int>(level); }

inline bool LogEnabled(LogLevel level) {
  return static_cast<int>(level) >= LogThreshold().load(std::memory_order_relaxed);
}

// Collects one message and writes it to stderr on destruction.
class LogMessage {
 public:
  explicit LogMessage(LogLevel level) : level_(level) {}
  ~LogMessage() {
    static std::mutex mutex;
    static constexpr const char* kPrefix[] = {"debug: ", "", "warning: ", "error: ", ""};
    std::string text = stream_.str();
    std::lock_guard<std::mutex> lock(mutex);
    std::fprintf(stderr, "%s%s\n", kPrefix[static_cast<int>(level_)], text.c_str());
  }
  LogMessage(const LogMessage&) = delete;
  LogMessage& operator=(const LogMessage&) = delete;
  std::ostringstream& stream() { return stream_; }

 private:
  LogLevel level_;
  std::ostringstream stream_;
};

}  // namespace netlab

#define NETLAB_LOG(level)                                 \
  if (!::netlab::LogEnabled(::netlab::LogLevel::level)) { \
  } else                                                  \
    ::netlab::LogMessage(::netlab::LogLevel::level).stream()
