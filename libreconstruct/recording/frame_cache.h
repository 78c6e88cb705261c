#pragma once
// A bounded cache of display frames with prefetching in the direction of play, so that scrubbing
// forwards and backwards through a recording stays smooth.
//
//   FrameCache cache(sequence, {.memory_limit_bytes = 2 << 30});
//   cache.SetPlayhead(frame, +1, level);            // the viewer moves forwards
//   auto image = cache.Get(camera, frame, level);   // decoded now, or already prefetched
//
// The cache never holds more than memory_limit_bytes of images (least recently used go first);
// an image handed out stays valid while the caller holds it. One worker thread decodes the
// frames ahead of the playhead (all cameras), up to half the budget, nearest first.

#include <condition_variable>
#include <list>
#include <map>
#include <memory>
#include <mutex>
#include <opencv2/core.hpp>
#include <set>
#include <string>
#include <thread>
#include <tuple>

#include "libreconstruct/recording/sequence.h"

namespace netlab::recon {

struct FrameCacheOptions {
  size_t memory_limit_bytes = size_t{2} << 30;  // 2 GiB
  int prefetch_ahead = 64;  // frames ahead of the playhead to decode (bounded by the budget)
  int prefetch_behind = 4;  // frames behind it
  bool prefetch = true;     // run the worker thread
};

class FrameCache {
 public:
  FrameCache(const SynchronizedSequence& sequence, FrameCacheOptions options);
  ~FrameCache();
  FrameCache(const FrameCache&) = delete;
  FrameCache& operator=(const FrameCache&) = delete;

  // The 8-bit BGR image of (camera, frame) at `level` (see SynchronizedSequence::ReadDisplay);
  // null with the reason in *error when the frame is missing or unreadable.
  std::shared_ptr<const cv::Mat> Get(int camera, int frame, int level,
                                     std::string* error = nullptr);
  // Where the viewer is and which way it moves (+1, -1, or 0 when still).
  void SetPlayhead(int frame, int direction, int level);

  struct Stats {
    long hits = 0, misses = 0, prefetched = 0, evicted = 0;
    size_t bytes = 0, peak_bytes = 0;
  };
  Stats stats() const;
  size_t limit() const { return options_.memory_limit_bytes; }

 private:
  using Key = std::tuple<int, int, int>;  // camera, frame, level
  struct Entry {
    std::shared_ptr<const cv::Mat> image;
    size_t bytes = 0;
    std::list<Key>::iterator lru;
  };
  // Decodes `key` unless cached or being decoded; waits for another thread's decoding.
  std::shared_ptr<const cv::Mat> Load(const Key& key, bool prefetch, std::string* error);
  void Insert(const Key& key, std::shared_ptr<const cv::Mat> image);  // lock held
  void Worker();

  const SynchronizedSequence& sequence_;
  FrameCacheOptions options_;
  mutable std::mutex mutex_;
  std::condition_variable changed_;
  std::map<Key, Entry> entries_;
  std::list<Key> lru_;  // front: most recent
  std::set<Key> in_flight_;
  Stats stats_;
  int playhead_ = 0, direction_ = 0, level_ = 0;
  long generation_ = 0;  // bumps on every playhead change
  bool stop_ = false;
  std::thread worker_;
};

}  // namespace netlab::recon
