#pragma once
// A limit on the size of every file this process and its children write (RLIMIT_FSIZE), restored
// on destruction. SIGXFSZ is ignored (and stays ignored across exec), so the write that crosses
// the limit fails with EFBIG, as a write to a full disk fails with ENOSPC, instead of killing the
// writer. The tests of a full disk use it.

#include <signal.h>
#include <sys/resource.h>

namespace netlab::testing {

class FileSizeLimit {
 public:
  explicit FileSizeLimit(long bytes) {
    getrlimit(RLIMIT_FSIZE, &old_);
    old_handler_ = signal(SIGXFSZ, SIG_IGN);
    rlimit limit = old_;
    limit.rlim_cur = static_cast<rlim_t>(bytes);
    setrlimit(RLIMIT_FSIZE, &limit);
  }
  FileSizeLimit(const FileSizeLimit&) = delete;
  FileSizeLimit& operator=(const FileSizeLimit&) = delete;
  ~FileSizeLimit() {
    setrlimit(RLIMIT_FSIZE, &old_);
    signal(SIGXFSZ, old_handler_);
  }

 private:
  rlimit old_;
  sighandler_t old_handler_;
};

}  // namespace netlab::testing
