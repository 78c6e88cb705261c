#pragma once
// The one progress printer of the commands, on stderr. A command's long call takes Reporter():
// its reports are printed here and Ctrl+C cancels it (InterruptToken). Nothing under --quiet.
//
// A report with a total reads "LABEL PERCENT DONE/TOTAL STAGE, DETAIL", the stage naming what is
// counted. On a terminal one line is redrawn in place, at most every 0.1 s, with a bar and an ETA
// (a new line for a new stage):
//   sweep [#########                     ]  31% 3.7/12 runs  ETA 0:42, 0 failed
// In a log (stderr not a terminal) a line at each tenth of a stage, with the seconds it has run:
//   sweep  30% 3.6/12 runs, 0 failed (18.2 s)
// A report without a total (the fit's iterations) is a sentence, in a log one line each:
//   fit: stage 1/3 material held, iteration 4, cost 812.3, 41 simulations, 20 s, ETA <= 3 min

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <mutex>
#include <string>

#include "app/command_line/command_line.h"
#include "common/progress.h"

namespace netlab::app {

class ProgressBar {
 public:
  // `label`: the command's name (or what it does); enabled false: print nothing (--quiet).
  ProgressBar(std::string label, bool enabled)
      : label_(std::move(label)), enabled_(enabled), tty_(isatty(fileno(stderr))) {}
  ~ProgressBar() { Break(); }
  ProgressBar(const ProgressBar&) = delete;
  ProgressBar& operator=(const ProgressBar&) = delete;

  // What a command hands its long call: reports printed here, cancelled by Ctrl+C. Reports may
  // come from any thread.
  ProgressReporter Reporter() {
    return ProgressReporter([this](const Progress& p) { Update(p); }, InterruptToken());
  }

  void Update(const Progress& p) {
    if (!enabled_) return;
    std::lock_guard<std::mutex> lock(mutex_);
    const Clock::time_point now = Clock::now();
    const bool new_stage = !started_ || p.stage != stage_;
    if (new_stage) {
      EndLine();
      started_ = true;
      stage_ = p.stage;
      stage_start_ = now;
      last_draw_ = Clock::time_point();
      last_tenth_ = -1;
      ended_ = false;
    }
    const double elapsed = std::chrono::duration<double>(now - stage_start_).count();
    const bool end = p.total > 0 && p.done >= p.total;
    if (tty_ && (ended_ || (!new_stage && !end && now - last_draw_ < kRedraw))) return;
    if (!tty_ && p.total > 0) {
      // A line at each tenth and at the end.
      const int tenth = end ? 10 : static_cast<int>(10 * p.fraction());
      if (tenth == last_tenth_) return;
      last_tenth_ = tenth;
    }
    std::string line;
    if (p.total > 0) {
      // "LABEL [####   ]  31% 3.7/12 runs  ETA 0:42, DETAIL" (a log: no bar, the seconds).
      line = label_ + " ";
      if (tty_) {
        constexpr int kWidth = 30;
        const int filled = static_cast<int>(kWidth * p.fraction());
        line += "[" + std::string(filled, '#') + std::string(kWidth - filled, ' ') + "] ";
      }
      line += Percent(p) + " " + Count(p.done) + "/" + Count(p.total);
      if (!p.stage.empty()) line += " " + p.stage;
      if (tty_ && p.done > 0 && !end)
        line += "  ETA " + Duration(elapsed * (p.total - p.done) / p.done);
      if (!p.detail.empty()) line += ", " + p.detail;
      if (!tty_) {
        char seconds[32];
        std::snprintf(seconds, sizeof seconds, " (%.1f s)", elapsed);
        line += seconds;
      }
    } else {
      // "LABEL: STAGE, DETAIL".
      line = label_ + ":";
      if (!p.stage.empty()) line += " " + p.stage;
      if (!p.detail.empty()) line += (p.stage.empty() ? " " : ", ") + p.detail;
    }
    if (tty_) {
      last_draw_ = now;
      std::fprintf(stderr, "\r%s\033[K", line.c_str());
      in_line_ = true;
      if (end) {
        EndLine();
        ended_ = true;  // until the next stage
      }
    } else {
      std::fprintf(stderr, "%s\n", line.c_str());
    }
    std::fflush(stderr);
  }

  // Ends a line drawn in place, so that what the command prints next starts on a line of its own.
  void Break() {
    std::lock_guard<std::mutex> lock(mutex_);
    EndLine();
  }

 private:
  using Clock = std::chrono::steady_clock;
  static constexpr std::chrono::milliseconds kRedraw{100};

  void EndLine() {
    if (!in_line_) return;
    std::fputc('\n', stderr);
    std::fflush(stderr);
    in_line_ = false;
  }
  static std::string Percent(const Progress& p) {
    char text[16];
    std::snprintf(text, sizeof text, "%3d%%", static_cast<int>(100 * p.fraction()));
    return text;
  }
  // A count as a whole number, or with one decimal while a unit is part done (3.4 runs).
  static std::string Count(double value) {
    char text[32];
    if (value == std::floor(value))
      std::snprintf(text, sizeof text, "%.0f", value);
    else
      std::snprintf(text, sizeof text, "%.1f", value);
    return text;
  }
  static std::string Duration(double seconds) {
    const long s = std::lround(std::max(0.0, seconds));
    char text[32];
    if (s >= 3600)
      std::snprintf(text, sizeof text, "%ld:%02ld:%02ld", s / 3600, s / 60 % 60, s % 60);
    else
      std::snprintf(text, sizeof text, "%ld:%02ld", s / 60, s % 60);
    return text;
  }

  std::string label_;
  bool enabled_, tty_;
  std::mutex mutex_;
  bool started_ = false, in_line_ = false, ended_ = false;
  std::string stage_;
  Clock::time_point stage_start_, last_draw_;
  int last_tenth_ = -1;
};

}  // namespace netlab::app
