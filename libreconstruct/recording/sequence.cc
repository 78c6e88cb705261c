#include "libreconstruct/recording/sequence.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstring>
#include <mutex>
#include <set>
#include <sstream>
#include <thread>

#include "common/errors.h"

namespace netlab::recon {
namespace {

// A fast 64-bit hash of a frame's bytes (duplicate detection, not security).
uint64_t HashFrame(const cv::Mat& m) {
  uint64_t h = 0x9E3779B97F4A7C15ull ^ static_cast<uint64_t>(m.total() * m.elemSize());
  for (int y = 0; y < m.rows; ++y) {
    const uint8_t* row = m.ptr<uint8_t>(y);
    const size_t bytes = m.cols * m.elemSize();
    size_t i = 0;
    for (; i + 8 <= bytes; i += 8) {
      uint64_t w;
      std::memcpy(&w, row + i, 8);
      h = (h ^ w) * 0x100000001B3ull;
      h ^= h >> 29;
    }
    for (; i < bytes; ++i) h = (h ^ row[i]) * 0x100000001B3ull;
  }
  return h;
}

std::string ListIndices(const std::vector<int>& v, size_t max = 12) {
  std::ostringstream os;
  for (size_t i = 0; i < v.size() && i < max; ++i) os << (i ? ", " : "") << v[i];
  if (v.size() > max) os << ", ... (" << v.size() << " in all)";
  return os.str();
}

}  // namespace

SynchronizedSequence::SynchronizedSequence(Experiment experiment)
    : experiment_(std::move(experiment)) {
  bool any = false;
  for (const CameraSpec& c : experiment_.cameras) {
    try {
      sources_.push_back(OpenFrameSource(c.frames, experiment_.base_dir));
    } catch (const InputError& e) {
      throw InputError(experiment_.path + ": camera " + c.name + ": " + e.what());
    }
    // A timestamps file, else the times the source carries (the frame store keeps them).
    timestamps_.push_back(c.timestamps.empty() ? sources_.back()->Timestamps()
                                               : ReadTimestamps(c.timestamps));
    const auto& idx = sources_.back()->indices();
    first_ = any ? std::min(first_, idx.front()) : idx.front();
    last_ = any ? std::max(last_, idx.back()) : idx.back();
    any = true;
    // Colour correction; the bit depth defaults to the first frame's container.
    ColorCorrection k;
    k.black_level = c.black_level;
    k.gains_bgr = {c.white_balance_rgb[2], c.white_balance_rgb[1], c.white_balance_rgb[0]};
    if (c.bit_depth) {
      k.bit_depth = *c.bit_depth;
    } else {
      FrameInfo info;
      std::string error;
      for (int i : idx)
        if (sources_.back()->Header(i, &info, &error)) break;
      k.bit_depth = info.depth == CV_16U ? 16 : 8;
      // Without bit_depth the file could not be checked: the frames' container says the depth.
      if (const std::string why = BlackLevelProblem(c.black_level, k.bit_depth); !why.empty())
        throw InputError((c.black_level_where.empty() ? experiment_.path + ": camera " + c.name
                                                      : c.black_level_where) +
                         ": " + why + " of " + c.name + "'s frames (" +
                         sources_.back()->Describe() + ")");
    }
    corrections_.push_back(k);
  }
}

bool SynchronizedSequence::Has(int camera, int frame) const {
  const auto& idx = sources_[camera]->indices();
  return std::binary_search(idx.begin(), idx.end(), frame);
}

cv::Mat SynchronizedSequence::ReadRaw(int camera, int frame, std::string* error) const {
  if (!Has(camera, frame)) {
    *error = "no frame " + std::to_string(frame);
    return {};
  }
  return sources_[camera]->Read(frame, error);
}

cv::Mat SynchronizedSequence::ReadDisplay(int camera, int frame, int level,
                                          std::string* error) const {
  const cv::Mat raw = ReadRaw(camera, frame, error);
  if (raw.empty()) return {};
  const BayerPattern bayer = experiment_.cameras[camera].bayer;
  if (level <= 0) return Demosaic(raw, bayer, corrections_[camera]);
  // Half resolution straight from the Bayer blocks, then halve again as needed.
  return Downscale(DemosaicHalf(raw, bayer, corrections_[camera]), 1 << (level - 1));
}

namespace {

// What checking one frame found: readable?, its size, its pixels' hash (when decoded).
struct FrameResult {
  bool ok = false;
  FrameInfo info;
  uint64_t hash = 0;
  std::string error;
};

// Marks frames unlike the camera's first readable frame (`reference`) as unreadable, and lists
// the unreadable, readable and duplicated (identical to the previous) frames in `cam`.
void SortFrames(const FrameSource& source, const std::vector<int>& idx, const FrameInfo& reference,
                bool decode, std::vector<FrameResult>& results, CameraReport& cam,
                std::set<int>& readable) {
  for (size_t k = 0; k < idx.size(); ++k) {
    FrameResult& r = results[k];
    if (r.ok && !(r.info == reference)) {
      r.ok = false;
      r.error = "size " + std::to_string(r.info.width) + "x" + std::to_string(r.info.height) +
                " differs from the camera's " + std::to_string(reference.width) + "x" +
                std::to_string(reference.height);
    }
    if (!r.ok) {
      cam.unreadable.push_back(idx[k]);
      cam.problems.push_back(cam.name + " frame " + std::to_string(idx[k]) + " (" +
                             source.Where(idx[k]) + "): " + r.error);
    } else {
      readable.insert(idx[k]);
      if (decode && k > 0 && results[k - 1].ok && results[k - 1].hash == r.hash &&
          idx[k - 1] == idx[k] - 1)
        cam.duplicated.push_back(idx[k]);  // identical to the previous frame
    }
  }
}

// Timestamps against the frame rate: a step under half a period is a duplicate, one over the
// frame count's periods plus a half a gap after the previous frame.
void CheckTimestamps(const std::vector<int>& idx, const std::map<int, double>& times, double fps,
                     CameraReport& cam) {
  if (times.empty()) return;
  const double period = 1.0 / fps;
  const int* previous = nullptr;
  for (const int& f : idx) {
    const auto it = times.find(f);
    if (it == times.end()) {
      cam.untimed.push_back(f);
      continue;
    }
    if (previous) {
      const double dt = it->second - times.at(*previous);
      const int steps = f - *previous;
      if (dt < 0.5 * period) {
        if (std::find(cam.duplicated.begin(), cam.duplicated.end(), f) == cam.duplicated.end())
          cam.duplicated.push_back(f);
      } else if (dt > (steps + 0.5) * period) {
        cam.timestamp_gaps.push_back(*previous);
      }
    }
    previous = &f;
  }
  std::sort(cam.duplicated.begin(), cam.duplicated.end());
}

// Warnings for cameras that differ from the first in frame size or count.
void CompareCameras(CheckReport& report) {
  for (size_t c = 1; c < report.cameras.size(); ++c) {
    const CameraReport& a = report.cameras[0];
    const CameraReport& b = report.cameras[c];
    if (a.width != b.width || a.height != b.height)
      report.warnings.push_back("cameras " + a.name + " and " + b.name + " differ in frame size (" +
                                std::to_string(a.width) + "x" + std::to_string(a.height) + " and " +
                                std::to_string(b.width) + "x" + std::to_string(b.height) + ")");
    if (a.frames != b.frames)
      report.warnings.push_back("cameras " + a.name + " and " + b.name +
                                " differ in frame count (" + std::to_string(a.frames) + " and " +
                                std::to_string(b.frames) + ")");
  }
}

}  // namespace

CheckReport SynchronizedSequence::Check(bool decode, const ProgressReporter& progress,
                                        int threads) const {
  const auto start = std::chrono::steady_clock::now();
  CheckReport report;
  report.first_frame = first_;
  report.last_frame = last_;
  report.decoded = decode;
  const int n = num_cameras();

  // Every frame of every camera, read (or only its header) on `threads` threads.
  std::vector<std::vector<FrameResult>> results(n);
  std::vector<std::pair<int, int>> tasks;  // (camera, position in its index list)
  for (int c = 0; c < n; ++c) {
    results[c].resize(sources_[c]->indices().size());
    for (size_t k = 0; k < results[c].size(); ++k) tasks.emplace_back(c, static_cast<int>(k));
  }
  std::atomic<int> next{0}, done{0};
  std::mutex mutex;
  auto worker = [&] {
    for (int t; !progress.cancelled() && (t = next++) < static_cast<int>(tasks.size());) {
      const auto [c, k] = tasks[t];
      const int index = sources_[c]->indices()[k];
      FrameResult& r = results[c][k];
      if (decode) {
        const cv::Mat raw = sources_[c]->Read(index, &r.error);
        if (!raw.empty()) {
          r.ok = true;
          r.info = FrameInfo{raw.cols, raw.rows, raw.depth(), raw.channels()};
          r.hash = HashFrame(raw);
          Demosaic(raw, experiment_.cameras[c].bayer, corrections_[c]);  // the decode cost
        }
      } else {
        r.ok = sources_[c]->Header(index, &r.info, &r.error);
      }
      const int d = ++done;
      if (progress.reports()) {
        std::lock_guard<std::mutex> lock(mutex);
        progress.Report(decode ? "frames decoded" : "frame headers read", d,
                        static_cast<double>(tasks.size()));
      }
    }
  };
  std::vector<std::thread> pool;
  for (int t = 1; t < std::max(1, threads); ++t) pool.emplace_back(worker);
  worker();
  for (std::thread& t : pool) t.join();
  progress.ThrowIfCancelled();

  // Per camera: its frame size (that of its first readable frame), then each frame's verdict,
  // the frames missing from the sequence's range, and the timestamps.
  std::vector<std::set<int>> readable(n);
  for (int c = 0; c < n; ++c) {
    CameraReport cam;
    cam.name = experiment_.cameras[c].name;
    const auto& idx = sources_[c]->indices();
    cam.frames = static_cast<int>(idx.size());
    FrameInfo reference;
    for (const FrameResult& r : results[c])
      if (r.ok) {
        reference = r.info;
        break;
      }
    cam.width = reference.width;
    cam.height = reference.height;
    cam.depth_bits = reference.depth == CV_16U ? 16 : 8;
    if (reference.channels == 3 && experiment_.cameras[c].bayer != BayerPattern::kNone)
      report.warnings.push_back(cam.name + ": the frames are already colour; bayer: " +
                                BayerPatternName(experiment_.cameras[c].bayer) + " is ignored");
    SortFrames(*sources_[c], idx, reference, decode, results[c], cam, readable[c]);
    for (int f = first_, k = 0; f <= last_; ++f) {
      while (k < static_cast<int>(idx.size()) && idx[k] < f) ++k;
      if (k >= static_cast<int>(idx.size()) || idx[k] != f) cam.missing.push_back(f);
    }
    CheckTimestamps(idx, timestamps_[c], experiment_.fps, cam);
    if (!experiment_.cameras[c].timestamps.empty() && timestamps_[c].empty())
      cam.untimed = idx;  // a timestamps file without a row
    if (!cam.untimed.empty())
      report.warnings.push_back(cam.name + ": " + std::to_string(cam.untimed.size()) + " of " +
                                std::to_string(cam.frames) + " frames have no time in " +
                                (experiment_.cameras[c].timestamps.empty()
                                     ? sources_[c]->Describe()
                                     : experiment_.cameras[c].timestamps) +
                                " (" + ListIndices(cam.untimed) + ")");
    report.frames_read += cam.frames;
    report.cameras.push_back(cam);
  }
  for (int f = first_; f <= last_; ++f) {
    bool all = true;
    for (int c = 0; c < n && all; ++c) all = readable[c].count(f) > 0;
    report.synchronized_frames += all;
  }
  CompareCameras(report);
  report.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  report.read_fps = report.wall_s > 0 ? report.frames_read / report.wall_s : 0.0;
  return report;
}

std::string CheckReport::BriefReport() const {
  std::ostringstream os;
  os << "frames " << first_frame << ".." << last_frame << ": " << synchronized_frames
     << " synchronized; " << frames_read << " frames " << (decoded ? "decoded" : "checked")
     << " at " << static_cast<int>(read_fps) << " frames/s\n";
  for (const CameraReport& c : cameras) {
    os << "  " << c.name << ": " << c.frames << " frames " << c.width << "x" << c.height << " ("
       << c.depth_bits << " bit)";
    if (!c.missing.empty()) os << "; missing " << ListIndices(c.missing);
    if (!c.unreadable.empty()) os << "; unreadable " << ListIndices(c.unreadable);
    if (!c.duplicated.empty()) os << "; duplicated " << ListIndices(c.duplicated);
    if (!c.timestamp_gaps.empty())
      os << "; timestamps skip after " << ListIndices(c.timestamp_gaps);
    if (!c.untimed.empty()) os << "; no timestamp " << ListIndices(c.untimed);
    os << "\n";
    for (size_t i = 0; i < c.problems.size() && i < 10; ++i) os << "    " << c.problems[i] << "\n";
    if (c.problems.size() > 10) os << "    ... " << c.problems.size() - 10 << " more\n";
  }
  for (const std::string& w : warnings) os << "  warning: " << w << "\n";
  return os.str();
}

}  // namespace netlab::recon
