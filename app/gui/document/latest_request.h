#pragma once
// The one way the workstation's long work leaves the GUI thread: run the latest request on a
// worker, drop stale answers, cancel on demand. A frame's decode, a knot's colour check, a Fill
// Grid preview and a tracking run each go through one of these.
//
//   LatestRequest<Image> loader(window, [window](Image image) { window->Show(image); });
//   loader.Request([t](const CancelToken& cancel) { return Decode(t, cancel); });
//
// One worker at a time per helper. A request made while one runs waits for it; only the newest
// waiting request is kept, and the running one's answer is dropped. Drop() forgets the wanted
// request: no answer comes. Cancel() cancels the running work's token (common/progress.h: the
// token a long library call polls); its answer still comes (a cancelled tracking run's frames are
// kept). Answers reach `answer` on the thread of `context`
// (the GUI thread) through its event loop: no blocking queued connection. The destructor cancels
// and waits for the worker.

#include <QFutureWatcher>
#include <QObject>
#include <QtConcurrent/QtConcurrent>
#include <functional>
#include <memory>
#include <optional>
#include <utility>

#include "common/progress.h"

namespace netlab::gui {

template <typename Result>
class LatestRequest {
 public:
  using Work = std::function<Result(const CancelToken& cancel)>;
  using Answer = std::function<void(Result)>;

  LatestRequest(QObject* context, Answer answer) : answer_(std::move(answer)) {
    QObject::connect(&watcher_, &QFutureWatcher<Result>::finished, context, [this] { Finished(); });
  }
  ~LatestRequest() {
    watcher_.disconnect();
    next_.reset();
    Cancel();
    watcher_.waitForFinished();
  }
  LatestRequest(const LatestRequest&) = delete;
  LatestRequest& operator=(const LatestRequest&) = delete;

  // Asks for `work`'s answer; any request before it is stale.
  void Request(Work work) {
    ++wanted_;
    pending_ = true;
    if (watcher_.isRunning()) {
      next_ = std::move(work);
      return;
    }
    Launch(std::move(work));
  }
  // Forgets the wanted request (a waiting one is never run; a running one's answer is dropped).
  void Drop() {
    ++wanted_;
    pending_ = false;
    next_.reset();
  }
  // Asks the running work to stop (its token); its answer still comes unless dropped.
  void Cancel() { cancel_.Cancel(); }
  // A worker is busy (with the wanted request or a stale one).
  bool running() const { return watcher_.isRunning(); }
  // A request is wanted and its answer has not been delivered yet.
  bool pending() const { return pending_; }
  // Blocks until the worker is free (the answer, if any, still comes through the event loop).
  void Wait() { watcher_.waitForFinished(); }

 private:
  void Launch(Work work) {
    launched_ = wanted_;
    cancel_ = CancelToken();  // a fresh token: an earlier Cancel() is not this work's
    watcher_.setFuture(
        QtConcurrent::run([work = std::move(work), cancel = cancel_] { return work(cancel); }));
  }
  void Finished() {
    if (next_) {  // a newer request waited: this answer is stale
      Work work = std::move(*next_);
      next_.reset();
      Launch(std::move(work));
      return;
    }
    if (launched_ != wanted_ || !pending_) return;  // dropped
    pending_ = false;
    answer_(watcher_.result());
  }

  Answer answer_;
  QFutureWatcher<Result> watcher_;
  std::optional<Work> next_;
  CancelToken cancel_;
  long wanted_ = 0, launched_ = 0;
  bool pending_ = false;
};

}  // namespace netlab::gui
