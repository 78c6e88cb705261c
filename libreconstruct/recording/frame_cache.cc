#include "libreconstruct/recording/frame_cache.h"

#include <algorithm>

namespace netlab::recon {

FrameCache::FrameCache(const SynchronizedSequence& sequence, FrameCacheOptions options)
    : sequence_(sequence), options_(options) {
  if (options_.prefetch) worker_ = std::thread([this] { Worker(); });
}

FrameCache::~FrameCache() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  changed_.notify_all();
  if (worker_.joinable()) worker_.join();
}

FrameCache::Stats FrameCache::stats() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return stats_;
}

void FrameCache::SetPlayhead(int frame, int direction, int level) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (frame == playhead_ && direction == direction_ && level == level_) return;
    playhead_ = frame;
    direction_ = direction;
    level_ = level;
    ++generation_;
  }
  changed_.notify_all();
}

std::shared_ptr<const cv::Mat> FrameCache::Get(int camera, int frame, int level,
                                               std::string* error) {
  std::string ignored;
  return Load(Key{camera, frame, level}, false, error ? error : &ignored);
}

void FrameCache::Insert(const Key& key, std::shared_ptr<const cv::Mat> image) {
  const size_t bytes = image->total() * image->elemSize();
  if (bytes > options_.memory_limit_bytes) return;  // larger than the whole budget
  while (stats_.bytes + bytes > options_.memory_limit_bytes && !lru_.empty()) {
    const Key victim = lru_.back();
    lru_.pop_back();
    stats_.bytes -= entries_[victim].bytes;
    entries_.erase(victim);
    ++stats_.evicted;
  }
  lru_.push_front(key);
  entries_[key] = Entry{std::move(image), bytes, lru_.begin()};
  stats_.bytes += bytes;
  stats_.peak_bytes = std::max(stats_.peak_bytes, stats_.bytes);
}

std::shared_ptr<const cv::Mat> FrameCache::Load(const Key& key, bool prefetch, std::string* error) {
  {
    std::unique_lock<std::mutex> lock(mutex_);
    // Another thread is decoding it: wait for that instead of decoding twice.
    changed_.wait(lock, [&] { return in_flight_.count(key) == 0; });
    const auto it = entries_.find(key);
    if (it != entries_.end()) {
      lru_.splice(lru_.begin(), lru_, it->second.lru);
      if (!prefetch) ++stats_.hits;
      return it->second.image;
    }
    if (!prefetch) ++stats_.misses;
    in_flight_.insert(key);
  }
  const auto [camera, frame, level] = key;
  cv::Mat image = sequence_.ReadDisplay(camera, frame, level, error);
  std::shared_ptr<const cv::Mat> result;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    in_flight_.erase(key);
    if (!image.empty()) {
      result = std::make_shared<const cv::Mat>(std::move(image));
      Insert(key, result);
      if (prefetch) ++stats_.prefetched;
    }
  }
  changed_.notify_all();
  return result;
}

void FrameCache::Worker() {
  std::unique_lock<std::mutex> lock(mutex_);
  long seen = -1;
  while (!stop_) {
    changed_.wait(lock, [&] { return stop_ || generation_ != seen; });
    if (stop_) return;
    seen = generation_;
    const int playhead = playhead_, direction = direction_, level = level_;
    lock.unlock();

    // The frames to have ready, nearest first: ahead in the direction of play, a few behind.
    const int cameras = sequence_.num_cameras();
    std::string error;
    size_t frame_bytes = 0;  // one frame of every camera at this level, learnt from the first
    const int step = direction >= 0 ? 1 : -1;
    bool moved = false;
    for (int d = 0; d <= options_.prefetch_ahead && !moved; ++d) {
      if (d > options_.prefetch_behind && direction == 0) break;
      const int frame = playhead + step * d;
      if (frame < sequence_.first_frame() || frame > sequence_.last_frame()) break;
      // Stay within half the budget, so prefetching never evicts what is being looked at.
      if (frame_bytes > 0 && (d + 1) * frame_bytes > options_.memory_limit_bytes / 2) break;
      size_t bytes = 0;
      for (int c = 0; c < cameras; ++c) {
        if (!sequence_.Has(c, frame)) continue;
        const auto image = Load(Key{c, frame, level}, true, &error);
        if (image) bytes += image->total() * image->elemSize();
      }
      frame_bytes = std::max(frame_bytes, bytes);
      std::lock_guard<std::mutex> check(mutex_);
      moved = stop_ || generation_ != seen;  // the viewer moved: start over from there
    }
    // A few frames behind, once the ones ahead are ready (they may have been evicted).
    for (int d = 1; d <= options_.prefetch_behind && direction != 0 && !moved; ++d) {
      const int frame = playhead - step * d;
      if (frame < sequence_.first_frame() || frame > sequence_.last_frame()) break;
      for (int c = 0; c < cameras; ++c)
        if (sequence_.Has(c, frame)) Load(Key{c, frame, level}, true, &error);
      std::lock_guard<std::mutex> check(mutex_);
      moved = stop_ || generation_ != seen;
    }
    lock.lock();
  }
}

}  // namespace netlab::recon
