#pragma once
// A progress bar on stderr for long commands: redrawn in place on a terminal, a line per 10 %
// otherwise (logs and CI).

#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <string>

namespace netlab::app {

class ProgressBar {
 public:
  ProgressBar(std::string label, bool enabled)
      : label_(std::move(label)),
        enabled_(enabled),
        tty_(isatty(fileno(stderr))),
        start_(std::chrono::steady_clock::now()) {}

  void Update(int done, int total) {
    if (!enabled_ || total <= 0) return;
    const double elapsed =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
    const int percent = static_cast<int>(100.0 * done / total);
    if (tty_) {
      if (done != total && elapsed - last_draw_ < 0.1) return;
      last_draw_ = elapsed;
      constexpr int kWidth = 30;
      const int filled = kWidth * done / total;
      const double rate = elapsed > 0 ? done / elapsed : 0.0;
      const int eta = rate > 0 ? static_cast<int>((total - done) / rate) : 0;
      std::fprintf(stderr, "\r%s [%s%s] %3d%% %d/%d  %.0f frames/s  ETA %d:%02d ", label_.c_str(),
                   std::string(filled, '#').c_str(), std::string(kWidth - filled, ' ').c_str(),
                   percent, done, total, rate, eta / 60, eta % 60);
      if (done == total) std::fputc('\n', stderr);
    } else {
      if (percent / 10 == last_decile_ && done != total) return;
      last_decile_ = percent / 10;
      std::fprintf(stderr, "%s %3d%% %d/%d (%.1f s)\n", label_.c_str(), percent, done, total,
                   elapsed);
    }
    std::fflush(stderr);
  }

 private:
  std::string label_;
  bool enabled_, tty_;
  std::chrono::steady_clock::time_point start_;
  double last_draw_ = -1.0;
  int last_decile_ = -1;
};

}  // namespace netlab::app
