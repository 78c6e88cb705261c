#pragma once
// Progress and cancellation of a long call, one way for every library: the call takes a
// ProgressReporter, reports a Progress (stage, done, total, an optional detail) through it and
// polls its CancelToken often enough that a cancel stops it within about a second. A cancelled
// call throws Cancelled; what it was writing is not put in place (its "<path>.partial" is
// removed). The command line's Ctrl+C and the window's Cancel buttons set the same token.
//
//   netlab::CancelToken cancel;  // shared: copies set and see the same flag
//   netlab::ProgressReporter reporter([](const netlab::Progress& p) { ... }, cancel);
//   for (int i = 0; i < n; ++i) {
//     reporter.ThrowIfCancelled();
//     ...
//     reporter.Report("detecting", i + 1, n);
//   }

#include <algorithm>
#include <atomic>
#include <exception>
#include <functional>
#include <memory>
#include <string>
#include <utility>

namespace netlab {

// One report of a long call.
struct Progress {
  std::string stage;   // what is under way ("simulating", "detecting", "rig"); may be empty
  double done = 0.0;   // units done: frames, images, runs, steps (a part-done unit may count part)
  double total = 0.0;  // units in all; <= 0: not known
  // A short text a printer shows beside the count, for calls that say more than a count (the
  // fit's cost and simulations); empty: none.
  std::string detail;

  // done / total in [0, 1]; 0 when the total is not known.
  double fraction() const { return total > 0 ? std::clamp(done / total, 0.0, 1.0) : 0.0; }
};

// What a cancelled call throws. Not a std::runtime_error, so the handlers that turn a failed part
// of a call into a result (a failed run of a sweep, an unreadable frame) let it through; the
// command runner prints "netlab NAME: cancelled" and exits 130 (docs/architecture.md, Errors).
class Cancelled : public std::exception {
 public:
  const char* what() const noexcept override { return "cancelled"; }
};

// A flag shared by its copies: Cancel() on any copy is seen by all, from any thread. Polling is
// one relaxed atomic load. A default-constructed token is a fresh flag nobody else holds.
class CancelToken {
 public:
  CancelToken() : flag_(std::make_shared<std::atomic<bool>>(false)) {}

  void Cancel() const { flag_->store(true, std::memory_order_relaxed); }
  bool cancelled() const { return flag_->load(std::memory_order_relaxed); }
  void ThrowIfCancelled() const {
    if (cancelled()) throw Cancelled();
  }
  // The flag itself, for a signal handler (a lock-free atomic store is async-signal-safe).
  std::atomic<bool>* flag() const { return flag_.get(); }

 private:
  std::shared_ptr<std::atomic<bool>> flag_;
};

// What a long call takes: where its reports go and the token it polls. The default reports to
// nobody and is never cancelled. Report() calls the callback on the reporting thread (each call
// says which thread that is); it does not poll the token.
class ProgressReporter {
 public:
  using Callback = std::function<void(const Progress&)>;

  ProgressReporter() = default;
  explicit ProgressReporter(Callback report, CancelToken cancel = CancelToken())
      : report_(std::move(report)), cancel_(std::move(cancel)) {}

  void Report(const Progress& progress) const {
    if (report_) report_(progress);
  }
  void Report(std::string stage, double done, double total, std::string detail = {}) const {
    if (report_) report_(Progress{std::move(stage), done, total, std::move(detail)});
  }
  bool reports() const { return static_cast<bool>(report_); }

  bool cancelled() const { return cancel_.cancelled(); }
  void ThrowIfCancelled() const { cancel_.ThrowIfCancelled(); }
  const CancelToken& cancel_token() const { return cancel_; }

  // The same token, the reports passed through `map` first (a part of a larger call reporting in
  // the larger call's units); reports nothing when this reporter reports nothing.
  ProgressReporter Mapped(std::function<Progress(Progress)> map) const {
    if (!report_) return ProgressReporter(Callback(), cancel_);
    return ProgressReporter(
        [report = report_, map = std::move(map)](const Progress& p) { report(map(p)); }, cancel_);
  }
  // The same token, no reports.
  ProgressReporter Silent() const { return ProgressReporter(Callback(), cancel_); }

 private:
  Callback report_;
  CancelToken cancel_;
};

}  // namespace netlab
