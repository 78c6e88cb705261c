#include "libreconstruct/recording/frame_cache.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <functional>
#include <random>
#include <string>
#include <thread>
#include <tuple>
#include <vector>

#include "tests/libreconstruct/test_files.h"

namespace netlab::recon {
namespace {

using testing::SameImage;
using testing::ScratchDir;
using testing::WritePgm;

constexpr int kWidth = 64, kHeight = 48, kFrames = 20;
constexpr size_t kFullFrameBytes = size_t{kWidth} * kHeight * 3;  // one level-0 BGR image

// Two cameras, frames 0..19 of noise (RGGB mosaics; a mix-up of frames, cameras or levels
// changes the pixels); camera 1 lacks frame 5.
class FrameCacheTest : public ::testing::Test {
 protected:
  FrameCacheTest() : dir_("frame_cache") {
    std::mt19937 random(7);
    for (int c = 0; c < 2; ++c)
      for (int k = 0; k < kFrames; ++k) {
        cv::Mat frame(kHeight, kWidth, CV_8UC1);
        for (int y = 0; y < kHeight; ++y)
          for (int x = 0; x < kWidth; ++x)
            frame.at<uint8_t>(y, x) = static_cast<uint8_t>(random() & 0xFF);
        if (c == 1 && k == 5) continue;
        char name[64];
        std::snprintf(name, sizeof(name), "cam%d/f_%03d.pgm", c, k);
        WritePgm(dir_ / name, frame);
      }
    Experiment e;
    e.name = "cache";
    e.fps = 100;
    e.base_dir = dir_.path().string();
    for (int c = 0; c < 2; ++c) {
      CameraSpec spec;
      spec.name = "cam" + std::to_string(c);
      spec.frames = spec.name + "/f_%03d.pgm";
      spec.bayer = BayerPattern::kRGGB;
      e.cameras.push_back(spec);
    }
    sequence_ = std::make_unique<SynchronizedSequence>(e);
  }

  cv::Mat Reference(int camera, int frame, int level) const {
    std::string error;
    return sequence_->ReadDisplay(camera, frame, level, &error);
  }

  // Polls `done` for up to 10 s.
  static bool WaitFor(const std::function<bool()>& done) {
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
    while (!done()) {
      if (std::chrono::steady_clock::now() > deadline) return false;
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
    }
    return true;
  }

  ScratchDir dir_;
  std::unique_ptr<SynchronizedSequence> sequence_;
};

TEST_F(FrameCacheTest, RandomAccessGivesTheSequencesImagesWithinTheBudget) {
  for (bool prefetch : {false, true}) {
    SCOPED_TRACE(prefetch ? "prefetching" : "no prefetching");
    FrameCacheOptions options;
    options.memory_limit_bytes = 5 * kFullFrameBytes;
    options.prefetch = prefetch;
    FrameCache cache(*sequence_, options);
    EXPECT_EQ(cache.limit(), 5 * kFullFrameBytes);

    std::vector<std::tuple<int, int, int>> keys;
    for (int c = 0; c < 2; ++c)
      for (int k = 0; k < kFrames; ++k)
        for (int level = 0; level < 3; ++level)
          if (!(c == 1 && k == 5)) keys.emplace_back(c, k, level);
    std::vector<std::tuple<int, int, int>> order = keys;
    order.insert(order.end(), keys.begin(), keys.end());
    std::shuffle(order.begin(), order.end(), std::mt19937(11));
    // Sequential playback too (the prefetcher follows), then random again.
    for (int k = 0; k < kFrames; ++k) order.emplace_back(0, k, 0);
    order.insert(order.end(), keys.rbegin(), keys.rend());

    int mismatches = 0;
    for (const auto& [c, k, level] : order) {
      if (prefetch) cache.SetPlayhead(k, +1, level);
      std::string error;
      const auto image = cache.Get(c, k, level, &error);
      ASSERT_TRUE(image) << "cam" << c << " frame " << k << " level " << level << ": " << error;
      if (!SameImage(*image, Reference(c, k, level))) ++mismatches;
      const FrameCache::Stats stats = cache.stats();
      ASSERT_LE(stats.bytes, options.memory_limit_bytes);
      ASSERT_LE(stats.peak_bytes, options.memory_limit_bytes);
    }
    EXPECT_EQ(mismatches, 0);
    const FrameCache::Stats stats = cache.stats();
    EXPECT_EQ(stats.hits + stats.misses, static_cast<long>(order.size()));
    EXPECT_GT(stats.evicted, 0) << "the budget should have forced evictions";
    EXPECT_GT(stats.peak_bytes, 3 * kFullFrameBytes) << "the budget should have been used";
    EXPECT_LE(stats.peak_bytes, options.memory_limit_bytes);
  }
}

TEST_F(FrameCacheTest, RepeatedGetIsAHitAndReturnsTheSameImage) {
  FrameCacheOptions options;
  options.prefetch = false;
  FrameCache cache(*sequence_, options);
  const auto first = cache.Get(0, 3, 1);
  const auto second = cache.Get(0, 3, 1);
  ASSERT_TRUE(first);
  EXPECT_EQ(first.get(), second.get());
  const FrameCache::Stats stats = cache.stats();
  EXPECT_EQ(stats.misses, 1);
  EXPECT_EQ(stats.hits, 1);
  EXPECT_EQ(stats.prefetched, 0);
  EXPECT_EQ(stats.bytes, kFullFrameBytes / 4);
}

TEST_F(FrameCacheTest, AnEvictedImageStaysValidForItsHolder) {
  FrameCacheOptions options;
  options.memory_limit_bytes = kFullFrameBytes;  // one image
  options.prefetch = false;
  FrameCache cache(*sequence_, options);
  const auto held = cache.Get(0, 0, 0);
  ASSERT_TRUE(held);
  for (int k = 1; k < 4; ++k) ASSERT_TRUE(cache.Get(0, k, 0));
  EXPECT_EQ(cache.stats().evicted, 3);
  EXPECT_EQ(cache.stats().bytes, kFullFrameBytes);
  EXPECT_TRUE(SameImage(*held, Reference(0, 0, 0)));
}

TEST_F(FrameCacheTest, PrefetchFollowsTheDirectionOfPlay) {
  FrameCacheOptions options;  // a budget far above the 20 frames
  options.prefetch_ahead = 64;
  options.prefetch_behind = 4;
  FrameCache cache(*sequence_, options);
  // Standing still at the start the worker prepares frames 0..4 (prefetch_behind frames ahead):
  // 10 images, camera 1 has them all.
  ASSERT_TRUE(WaitFor([&] { return cache.stats().prefetched >= 10; }));

  // Forwards from 10: 10..19 ahead (20 images), 9..6 behind (8 images).
  cache.SetPlayhead(10, +1, 0);
  ASSERT_TRUE(WaitFor([&] { return cache.stats().prefetched >= 38; })) << cache.stats().prefetched;
  for (int k = 10; k < kFrames; ++k)
    for (int c = 0; c < 2; ++c) {
      const auto image = cache.Get(c, k, 0);
      ASSERT_TRUE(image);
      EXPECT_TRUE(SameImage(*image, Reference(c, k, 0)));
    }
  FrameCache::Stats stats = cache.stats();
  EXPECT_EQ(stats.hits, 20);
  EXPECT_EQ(stats.misses, 0);

  // Backwards from 10: only frame 5 is new (camera 0 only: camera 1 lacks it).
  cache.SetPlayhead(10, -1, 0);
  ASSERT_TRUE(WaitFor([&] { return cache.stats().prefetched >= 39; })) << cache.stats().prefetched;
  for (int k = 9; k >= 0; --k)
    for (int c = 0; c < 2; ++c)
      if (!(c == 1 && k == 5)) {
        const auto image = cache.Get(c, k, 0);
        ASSERT_TRUE(image);
        EXPECT_TRUE(SameImage(*image, Reference(c, k, 0)));
      }
  stats = cache.stats();
  EXPECT_EQ(stats.hits, 20 + 19);
  EXPECT_EQ(stats.misses, 0);

  // A new level: prefetched at that level from the playhead.
  cache.SetPlayhead(0, +1, 2);
  ASSERT_TRUE(WaitFor([&] { return cache.stats().prefetched >= 39 + 39; }))
      << cache.stats().prefetched;
  const auto small = cache.Get(1, 19, 2);
  ASSERT_TRUE(small);
  EXPECT_EQ(small->size(), cv::Size(kWidth / 4, kHeight / 4));
  EXPECT_EQ(cache.stats().misses, 0);
}

TEST_F(FrameCacheTest, SequentialPlaybackWithPrefetchStaysWithinTheBudget) {
  FrameCacheOptions options;
  options.memory_limit_bytes = 8 * kFullFrameBytes;  // 4 frames of both cameras
  FrameCache cache(*sequence_, options);
  for (int k = 0; k < kFrames; ++k) {
    cache.SetPlayhead(k, +1, 0);
    for (int c = 0; c < 2; ++c) {
      std::string error;
      const auto image = cache.Get(c, k, 0, &error);
      if (c == 1 && k == 5) {
        EXPECT_FALSE(image);
        continue;
      }
      ASSERT_TRUE(image) << error;
      EXPECT_TRUE(SameImage(*image, Reference(c, k, 0)));
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  const FrameCache::Stats stats = cache.stats();
  EXPECT_LE(stats.peak_bytes, options.memory_limit_bytes);
  EXPECT_GT(stats.prefetched, 0);
}

TEST_F(FrameCacheTest, MissingFrameIsNullWithTheReason) {
  FrameCacheOptions options;
  FrameCache cache(*sequence_, options);
  std::string error;
  EXPECT_FALSE(cache.Get(1, 5, 0, &error));
  EXPECT_EQ(error, "no frame 5");
  error.clear();
  EXPECT_FALSE(cache.Get(0, kFrames, 1, &error));
  EXPECT_FALSE(error.empty());
  EXPECT_FALSE(cache.Get(0, -1, 0));  // no error pointer: still null, no crash
  EXPECT_TRUE(cache.Get(1, 6, 0));
}

TEST_F(FrameCacheTest, ConcurrentGetsFromTwoThreadsAreSafe) {
  std::vector<cv::Mat> reference[2][3];
  for (int c = 0; c < 2; ++c)
    for (int level = 0; level < 3; ++level)
      for (int k = 0; k < kFrames; ++k) reference[c][level].push_back(Reference(c, k, level));
  FrameCacheOptions options;
  options.memory_limit_bytes = 6 * kFullFrameBytes;  // small: evictions while others read
  FrameCache cache(*sequence_, options);
  std::atomic<int> mismatches{0}, wrong_nulls{0}, gets{0};
  auto reader = [&](unsigned seed) {
    std::mt19937 random(seed);
    for (int i = 0; i < 400; ++i) {
      const int c = static_cast<int>(random() % 2), k = static_cast<int>(random() % kFrames);
      const int level = static_cast<int>(random() % 3);
      if (i % 16 == 0) cache.SetPlayhead(k, (random() % 2) ? +1 : -1, level);
      std::string error;
      const auto image = cache.Get(c, k, level, &error);
      ++gets;
      if (c == 1 && k == 5) {
        if (image) ++wrong_nulls;
        continue;
      }
      if (!image) {
        ++wrong_nulls;
        continue;
      }
      if (!SameImage(*image, reference[c][level][k])) ++mismatches;
    }
  };
  std::thread other(reader, 1u);
  reader(2u);
  other.join();
  EXPECT_EQ(mismatches.load(), 0);
  EXPECT_EQ(wrong_nulls.load(), 0);
  const FrameCache::Stats stats = cache.stats();
  EXPECT_EQ(stats.hits + stats.misses, gets.load());
  EXPECT_LE(stats.peak_bytes, options.memory_limit_bytes);
}

}  // namespace
}  // namespace netlab::recon
