// Ingestion benchmark: how fast a four-camera 2048 x 2048 Bayer recording plays from page cache.
//
//   bench_ingest [--frames N] [--dir DIR] [--keep]
//
// Writes a synthetic recording (4 cameras x N frames, default 90, 8-bit RGGB PGM; a 12-bit copy
// in 16-bit PGM and HDF5 frame stores converted from it), reads it once to warm the page cache,
// then measures:
// A. memory bandwidth (memcpy of 256 MB): the ceiling for any frame path;
// B. one camera on one thread: read, read + demosaic at full and half resolution, sequential
//    and random order, per source format, in frames/s and raw MB/s;
// C. four cameras together on 2 threads (one synchronized frame = 4 camera frames), sequential
//    and random, full and half resolution: the targets are >= 60 synchronized frames/s
//    sequentially at full resolution and >= 30 at half resolution under random access;
// D. the frame cache as the viewer uses it: play forwards, then backwards (prefetching), and
//    random scrubbing, with the cache's peak bytes and the process's peak resident memory.

#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <numeric>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <random>
#include <thread>
#include <vector>

#include "libreconstruct/recording/frame_cache.h"
#include "libreconstruct/recording/frame_store.h"
#include "libreconstruct/recording/sequence.h"

namespace netlab::recon {
namespace {

namespace fs = std::filesystem;
constexpr int kSize = 2048, kCameras = 4;

double Seconds(std::chrono::steady_clock::time_point since) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - since).count();
}

// Peak resident memory of this process (VmHWM), MB.
double PeakResidentMb() {
  std::ifstream status("/proc/self/status");
  for (std::string line; std::getline(status, line);)
    if (line.rfind("VmHWM:", 0) == 0) return std::stod(line.substr(6)) / 1024.0;
  return 0.0;
}

// A scene a camera might see: dark background, smooth vignetting, bright thin lines (a net),
// sensor noise; mosaicked RGGB. Each frame differs (the lines move).
cv::Mat SceneMosaic(int camera, int frame, int depth, const cv::Mat& noise) {
  cv::Mat bgr(kSize, kSize, CV_8UC3, cv::Scalar(20, 22, 25));
  for (int i = 0; i < 24; ++i) {
    const int offset = 60 + i * 80 + 3 * frame + 7 * camera;
    const cv::Scalar colour(40 + 9 * i % 200, 200 - 7 * i % 150, 90 + 13 * i % 160);
    cv::line(bgr, {offset, 0}, {offset + 300, kSize - 1}, colour, 3, cv::LINE_AA);
    cv::line(bgr, {0, offset}, {kSize - 1, offset - 200}, colour, 3, cv::LINE_AA);
  }
  bgr += noise;
  cv::Mat mosaic = Mosaic(bgr, BayerPattern::kRGGB);
  if (depth == CV_16U) mosaic.convertTo(mosaic, CV_16U, 16.0);  // 12-bit data in 16-bit words
  return mosaic;
}

void WriteRecording(const fs::path& dir, int frames, int depth) {
  fs::create_directories(dir);
  cv::Mat noise(kSize, kSize, CV_8UC3);
  cv::randn(noise, 0, 3);
  std::ofstream yaml(dir / "experiment.yaml");
  yaml << "experiment: bench\nfps: 179\ncameras:\n";
  for (int c = 0; c < kCameras; ++c) {
    const std::string name = "cam" + std::to_string(c);
    fs::create_directories(dir / name);
    yaml << "  - name: " << name << "\n    frames: " << name << "/frame_%06d.pgm\n"
         << "    bayer: RGGB\n"
         << (depth == CV_16U ? "    bit_depth: 12\n" : "");
    for (int k = 0; k < frames; ++k) {
      char file[64];
      std::snprintf(file, sizeof(file), "frame_%06d.pgm", k);
      if (!fs::exists(dir / name / file))
        cv::imwrite((dir / name / file).string(), SceneMosaic(c, k, depth, noise));
    }
  }
}

// Every file read once so the measurements run from page cache.
void WarmPageCache(const fs::path& dir) {
  std::vector<char> buffer(1 << 22);
  for (const auto& entry : fs::recursive_directory_iterator(dir))
    if (entry.is_regular_file()) {
      std::ifstream in(entry.path(), std::ios::binary);
      while (in.read(buffer.data(), buffer.size())) {
      }
    }
}

double MemcpyGBs() {
  const size_t bytes = size_t{256} << 20;
  std::vector<char> a(bytes, 1), b(bytes, 2);
  std::memcpy(b.data(), a.data(), bytes);
  const auto start = std::chrono::steady_clock::now();
  const int repeats = 8;
  for (int r = 0; r < repeats; ++r)
    std::memcpy((r % 2 ? a : b).data(), (r % 2 ? b : a).data(), bytes);
  return repeats * bytes / Seconds(start) / 1e9;
}

enum class Work { kRead, kFull, kHalf };

// Runs `work` on camera frames `order` (pairs of camera, frame) on `threads` threads; returns
// camera frames per second.
double Run(const SynchronizedSequence& seq, const std::vector<std::pair<int, int>>& order,
           Work work, int threads) {
  std::atomic<int> next{0}, failed{0};
  const auto start = std::chrono::steady_clock::now();
  auto worker = [&] {
    std::string error;
    for (int t; (t = next++) < static_cast<int>(order.size());) {
      const auto [c, k] = order[t];
      const cv::Mat m = work == Work::kRead
                            ? seq.ReadRaw(c, k, &error)
                            : seq.ReadDisplay(c, k, work == Work::kHalf ? 1 : 0, &error);
      if (m.empty()) ++failed;
    }
  };
  std::vector<std::thread> pool;
  for (int t = 1; t < threads; ++t) pool.emplace_back(worker);
  worker();
  for (std::thread& t : pool) t.join();
  if (failed) std::fprintf(stderr, "warning: %d frames failed to read\n", failed.load());
  return order.size() / Seconds(start);
}

// Camera frames in synchronized order (frame k of every camera, then k + 1), sequential or
// shuffled by frame.
std::vector<std::pair<int, int>> Order(int cameras, int frames, bool random, int passes = 1) {
  std::vector<int> k(frames);
  std::iota(k.begin(), k.end(), 0);
  std::vector<std::pair<int, int>> order;
  std::mt19937 rng(7);
  for (int p = 0; p < passes; ++p) {
    if (random) std::shuffle(k.begin(), k.end(), rng);
    for (int f : k)
      for (int c = 0; c < cameras; ++c) order.emplace_back(c, f);
  }
  return order;
}

double RawMb(const SynchronizedSequence& seq) {
  std::string error;
  const cv::Mat m = seq.ReadRaw(0, 0, &error);
  return m.total() * m.elemSize() / 1e6;
}

}  // namespace
}  // namespace netlab::recon

int main(int argc, char** argv) {
  using namespace netlab::recon;
  namespace fs = std::filesystem;
  int frames = 90;
  fs::path dir = fs::temp_directory_path() / "netlab_ingest_bench";
  bool keep = false;
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--frames") && i + 1 < argc)
      frames = std::max(8, std::atoi(argv[++i]));
    if (!std::strcmp(argv[i], "--dir") && i + 1 < argc) dir = argv[++i];
    if (!std::strcmp(argv[i], "--keep")) keep = true;
  }
  const unsigned cores = std::max(1u, std::thread::hardware_concurrency());
  const int threads = std::min(2u, cores);
  std::printf("ingestion benchmark: %d cameras x %d frames of %dx%d RGGB, %u cores, %d threads\n",
              kCameras, frames, kSize, kSize, cores, threads);
  std::printf("recording in %s\n\n", dir.string().c_str());

  auto t0 = std::chrono::steady_clock::now();
  WriteRecording(dir / "pgm8", frames, CV_8U);
  WriteRecording(dir / "pgm16", std::min(frames, 40), CV_16U);
  std::printf("wrote the PGM recordings in %.1f s\n", Seconds(t0));
  {
    const SynchronizedSequence pgm(LoadExperiment((dir / "pgm8/experiment.yaml").string()));
    for (int level : {0, 1}) {
      const fs::path out = dir / (level ? "store_gzip1.h5" : "store.h5");
      if (fs::exists(out)) continue;
      t0 = std::chrono::steady_clock::now();
      const Experiment e = ConvertToFrameStore(pgm, out.string(), {level}, {});
      WriteExperiment(e.path, e);
      std::printf("converted to %s (gzip %d): %.1f s, %.0f MB, %.0f camera frames/s\n",
                  out.filename().c_str(), level, Seconds(t0), fs::file_size(out) / 1e6,
                  kCameras * frames / Seconds(t0));
    }
  }
  WarmPageCache(dir);

  const double bandwidth = MemcpyGBs();
  std::printf(
      "\nA. memory bandwidth: memcpy %.1f GB/s (read + write). A 4.2 MB frame read once and\n"
      "   written once costs at least %.2f ms: at most %.0f camera frames/s per core.\n\n",
      bandwidth, 2 * 4.194 / bandwidth, bandwidth * 1e3 / (2 * 4.194));

  struct Source {
    const char* name;
    std::string experiment;
  };
  const std::vector<Source> sources = {
      {"PGM 8-bit", (dir / "pgm8/experiment.yaml").string()},
      {"PGM 16-bit (12 used)", (dir / "pgm16/experiment.yaml").string()},
      {"HDF5 store", (dir / "store.yaml").string()},
      {"HDF5 store gzip 1", (dir / "store_gzip1.yaml").string()},
  };

  std::printf("B. one camera, one thread (camera frames/s; raw MB/s in brackets)\n\n");
  std::printf(
      "| source               | order      | read            | read+demosaic full | read+half res  "
      " |\n");
  std::printf(
      "|----------------------|------------|-----------------|--------------------|----------------"
      "-|\n");
  for (const Source& s : sources) {
    const SynchronizedSequence seq(LoadExperiment(s.experiment));
    const int n = seq.last_frame() + 1;
    const double mb = RawMb(seq);
    for (bool random : {false, true}) {
      const auto order = Order(1, n, random);
      const double read = Run(seq, order, Work::kRead, 1);
      const double full = Run(seq, order, Work::kFull, 1);
      const double half = Run(seq, order, Work::kHalf, 1);
      std::printf("| %-20s | %-10s | %6.0f (%5.0f)  | %7.0f (%5.0f)    | %6.0f (%5.0f)  |\n",
                  s.name, random ? "random" : "sequential", read, read * mb, full, full * mb, half,
                  half * mb);
    }
  }

  std::printf(
      "\nC. four cameras together, %d threads (synchronized frames/s = camera frames/s / 4)\n\n",
      threads);
  std::printf(
      "| source               | order      | full res sync fps | half res sync fps | full MB/s "
      "|\n");
  std::printf(
      "|----------------------|------------|-------------------|-------------------|-----------|"
      "\n");
  double target_full = 0, target_half_random = 0;
  for (const Source& s : sources) {
    const SynchronizedSequence seq(LoadExperiment(s.experiment));
    const int n = seq.last_frame() + 1;
    const double mb = RawMb(seq);
    for (bool random : {false, true}) {
      const auto order = Order(kCameras, n, random);
      const double full = Run(seq, order, Work::kFull, threads) / kCameras;
      const double half = Run(seq, order, Work::kHalf, threads) / kCameras;
      if (&s == &sources[0] && !random) target_full = full;
      if (&s == &sources[0] && random) target_half_random = half;
      std::printf("| %-20s | %-10s | %17.0f | %17.0f | %9.0f |\n", s.name,
                  random ? "random" : "sequential", full, half, full * kCameras * mb);
    }
  }
  std::printf(
      "\ntargets (PGM 8-bit): sequential full res %.0f sync fps (>= 60: %s), random half res "
      "%.0f sync fps (>= 30: %s)\n",
      target_full, target_full >= 60 ? "met" : "NOT met", target_half_random,
      target_half_random >= 30 ? "met" : "NOT met");

  std::printf(
      "\nD. the frame cache as the viewer uses it (PGM 8-bit, 4 cameras per displayed frame)\n\n");
  std::printf(
      "| level | limit MiB | access                   | sync fps | hit rate | worst ms | cache "
      "peak MiB | RSS peak MiB |\n");
  std::printf(
      "|-------|-----------|--------------------------|----------|----------|----------|-----------"
      "-----|--------------|\n");
  {
    const SynchronizedSequence seq(LoadExperiment(sources[0].experiment));
    const int n = seq.last_frame() + 1;
    for (int level : {0, 1}) {
      const size_t limit = (level == 0 ? size_t{512} : size_t{256}) << 20;
      FrameCache cache(seq, {.memory_limit_bytes = limit});
      // Plays (frame, direction of play) steps, fetching every camera's image of each frame, as
      // fast as possible (pace 0) or at `pace` displayed frames/s (the viewer's timer). Reports
      // the rate, the share of images already decoded, and the slowest frame's wait.
      auto play = [&](const char* what, const std::vector<std::pair<int, int>>& frames_in_order,
                      double pace) {
        const auto before = cache.stats();
        const auto start = std::chrono::steady_clock::now();
        double worst_ms = 0.0;
        for (size_t i = 0; i < frames_in_order.size(); ++i) {
          const auto [f, direction] = frames_in_order[i];
          if (pace > 0)
            std::this_thread::sleep_until(start +
                                          std::chrono::duration_cast<std::chrono::nanoseconds>(
                                              std::chrono::duration<double>(i / pace)));
          const auto asked = std::chrono::steady_clock::now();
          cache.SetPlayhead(f, direction, level);
          for (int c = 0; c < kCameras; ++c)
            if (!cache.Get(c, f, level)) std::fprintf(stderr, "warning: frame %d missing\n", f);
          worst_ms = std::max(worst_ms, 1e3 * Seconds(asked));
        }
        const double fps = frames_in_order.size() / Seconds(start);
        const auto after = cache.stats();
        const long hits = after.hits - before.hits, misses = after.misses - before.misses;
        std::printf("| %5d | %9zu | %-24s | %8.0f | %7.0f%% | %9.1f | %14.0f | %12.0f |\n", level,
                    limit >> 20, what, fps, 100.0 * hits / std::max(1L, hits + misses), worst_ms,
                    after.peak_bytes / 1048576.0, PeakResidentMb());
      };
      std::vector<std::pair<int, int>> forwards, backwards, random, bursts;
      for (int f = 0; f < n; ++f) forwards.emplace_back(f, +1);
      for (int f = n - 1; f >= 0; --f) backwards.emplace_back(f, -1);
      for (int f = 0; f < n; ++f) random.emplace_back(f, 0);
      std::shuffle(random.begin(), random.end(), std::mt19937(3));
      // A person scrubbing: bursts of 10 frames forwards or backwards from random places.
      std::mt19937 rng(4);
      for (int b = 0; b < n / 10; ++b) {
        const int at = std::uniform_int_distribution<int>(10, n - 11)(rng);
        const int way = b % 2 ? 1 : -1;
        for (int i = 0; i < 10; ++i) bursts.emplace_back(at + way * i, way);
      }
      play("play forwards", forwards, 0);
      play("play backwards", backwards, 0);
      play("play forwards at 60/s", forwards, 60);
      play("play backwards at 60/s", backwards, 60);
      play("random scrubbing", random, 0);
      play("bursts of 10, +/-", bursts, 0);
    }
  }
  if (!keep) fs::remove_all(dir);
  return 0;
}
