#include "libnetsim/sweep/sweep_runner.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstring>
#include <deque>
#include <exception>
#include <mutex>
#include <stdexcept>
#include <thread>
#include <type_traits>

#include "common/errors.h"
#include "libnetsim/sweep/sweep_mpi.h"

namespace netlab::netsim {
namespace {

using Clock = std::chrono::steady_clock;

// The messages between ranks (sweep_mpi.h): a rank asks rank 0 for a run index (kAsk), rank 0
// answers with one or -1 when none is left (kIndex), the rank sends the finished run back
// (kResult) and, when it has nothing more to do, says so (kBye).
enum Tag { kAsk = 1, kIndex = 2, kResult = 3, kBye = 4 };

// Types sent as their bytes: the trivially copyable ones and Eigen's fixed vectors (3 doubles).
template <typename T>
constexpr bool kRaw = std::is_trivially_copyable_v<T> || std::is_same_v<T, Vector3d>;

// A run as bytes, to send it between ranks: plain values copied, vectors and strings with their
// sizes first. Every rank is the same binary on one kind of machine.
class Bytes {
 public:
  template <typename T>
  void Put(const T& value) {
    static_assert(kRaw<T>);
    out_.append(reinterpret_cast<const char*>(&value), sizeof(T));
  }
  void Put(const std::string& s) {
    Put(static_cast<uint64_t>(s.size()));
    out_ += s;
  }
  template <typename T>
  void Put(const std::vector<T>& v) {
    Put(static_cast<uint64_t>(v.size()));
    if constexpr (kRaw<T>) {
      out_.append(reinterpret_cast<const char*>(v.data()), v.size() * sizeof(T));
    } else {
      for (const T& item : v) Put(item);
    }
  }
  const std::string& str() const { return out_; }

 private:
  std::string out_;
};

class Reader {
 public:
  explicit Reader(const std::string& in) : in_(in) {}
  template <typename T>
  void Get(T* value) {
    static_assert(kRaw<T>);
    Need(sizeof(T));
    std::memcpy(static_cast<void*>(value), in_.data() + pos_, sizeof(T));
    pos_ += sizeof(T);
  }
  void Get(std::string* s) {
    uint64_t n = 0;
    Get(&n);
    Need(n);
    s->assign(in_, pos_, n);
    pos_ += n;
  }
  template <typename T>
  void Get(std::vector<T>* v) {
    uint64_t n = 0;
    Get(&n);
    if constexpr (kRaw<T>) {
      Need(n * sizeof(T));
      v->resize(n);
      std::memcpy(static_cast<void*>(v->data()), in_.data() + pos_, n * sizeof(T));
      pos_ += n * sizeof(T);
    } else {
      v->resize(n);
      for (T& item : *v) Get(&item);
    }
  }

 private:
  void Need(size_t n) const {
    if (pos_ + n > in_.size()) throw std::runtime_error("sweep: a truncated message from a rank");
  }
  const std::string& in_;
  size_t pos_ = 0;
};

std::string Serialize(const SweepRun& run) {
  Bytes b;
  b.Put(run.index);
  b.Put(static_cast<int>(run.status));
  b.Put(run.error);
  b.Put(static_cast<uint64_t>(run.overrides.size()));
  for (const ScenarioOverride& o : run.overrides) {
    b.Put(o.path);
    b.Put(o.value);
  }
  const RunSummary& s = run.summary;
  b.Put(s.scenario);
  b.Put(s.stable);
  b.Put(s.error);
  b.Put(s.integrator);
  for (double v : {s.dt, s.dt_limit, s.max_inertia_scale, s.sim_time, s.wall_s,
                   s.segment_steps_per_s, s.real_time_factor, s.max_penetration, s.contact_start_s,
                   s.energy.kinetic, s.energy.elastic, s.energy.potential})
    b.Put(v);
  b.Put(s.steps);
  for (int v : {s.nodes, s.segments, s.knots, s.frames}) b.Put(v);
  b.Put(s.max_penetration_at);
  b.Put(s.active);
  b.Put(static_cast<uint64_t>(s.probes.size()));
  for (const auto& [name, p] : s.probes) {
    b.Put(name);
    b.Put(p);
  }
  b.Put(run.outputs);
  b.Put(run.time);
  b.Put(run.knots);
  b.Put(run.grid);
  b.Put(run.net);
  b.Put(run.rank);
  return b.str();
}

SweepRun Deserialize(const std::string& bytes) {
  Reader r(bytes);
  SweepRun run;
  r.Get(&run.index);
  int status = 0;
  r.Get(&status);
  run.status = static_cast<SweepRun::Status>(status);
  r.Get(&run.error);
  uint64_t n = 0;
  r.Get(&n);
  run.overrides.resize(n);
  for (ScenarioOverride& o : run.overrides) {
    r.Get(&o.path);
    r.Get(&o.value);
  }
  RunSummary& s = run.summary;
  r.Get(&s.scenario);
  r.Get(&s.stable);
  r.Get(&s.error);
  r.Get(&s.integrator);
  for (double* v : {&s.dt, &s.dt_limit, &s.max_inertia_scale, &s.sim_time, &s.wall_s,
                    &s.segment_steps_per_s, &s.real_time_factor, &s.max_penetration,
                    &s.contact_start_s, &s.energy.kinetic, &s.energy.elastic, &s.energy.potential})
    r.Get(v);
  r.Get(&s.steps);
  for (int* v : {&s.nodes, &s.segments, &s.knots, &s.frames}) r.Get(v);
  r.Get(&s.max_penetration_at);
  r.Get(&s.active);
  r.Get(&n);
  s.probes.resize(n);
  for (auto& [name, p] : s.probes) {
    r.Get(&name);
    r.Get(&p);
  }
  r.Get(&run.outputs);
  r.Get(&run.time);
  r.Get(&run.knots);
  r.Get(&run.grid);
  r.Get(&run.net);
  r.Get(&run.rank);
  return run;
}

std::string IntBytes(int value) {
  Bytes b;
  b.Put(value);
  return b.str();
}
int BytesInt(const std::string& bytes) {
  int value = 0;
  Reader(bytes).Get(&value);
  return value;
}

// The pool of one process: `jobs` threads take run indices from `next` (-1: no more) and leave
// the finished runs for the calling thread, which collects them with Take.
class Pool {
 public:
  Pool(const std::string& scenario_path, const std::vector<std::vector<ScenarioOverride>>& runs,
       int jobs, int decimate, int rank, std::function<int()> next, const CancelToken& cancel)
      : fractions_(runs.size()) {
    for (auto& f : fractions_) f = 0.0;
    for (int j = 0; j < jobs; ++j)
      threads_.emplace_back([this, &scenario_path, &runs, decimate, rank, next, cancel] {
        for (int i = next(); i >= 0; i = next()) {
          SweepRun run;
          try {
            run =
                RunOne(scenario_path, i, runs[i], decimate,
                       ProgressReporter(
                           [this, i](const Progress& p) { fractions_[i] = p.fraction(); }, cancel));
          } catch (const Cancelled&) {
            break;  // the calling thread sees the token and throws
          }
          run.rank = rank;
          fractions_[i] = 0.0;
          std::lock_guard<std::mutex> lock(mutex_);
          done_.push_back(std::move(run));
          ready_.notify_all();
        }
        std::lock_guard<std::mutex> lock(mutex_);
        ++exited_;
        ready_.notify_all();
      });
  }
  ~Pool() {
    for (std::thread& t : threads_) t.join();
  }

  // The runs finished since the last call, waiting up to `wait` for one.
  std::vector<SweepRun> Take(std::chrono::milliseconds wait) {
    std::unique_lock<std::mutex> lock(mutex_);
    ready_.wait_for(lock, wait, [this] { return !done_.empty() || exited_ == threads_.size(); });
    std::vector<SweepRun> out(std::make_move_iterator(done_.begin()),
                              std::make_move_iterator(done_.end()));
    done_.clear();
    return out;
  }
  bool Exited() {
    std::lock_guard<std::mutex> lock(mutex_);
    return exited_ == threads_.size() && done_.empty();
  }
  // The parts of the runs under way, summed.
  double UnderWay() const {
    double sum = 0;
    for (const auto& f : fractions_) sum += f;
    return sum;
  }

 private:
  std::vector<std::atomic<double>> fractions_;
  std::mutex mutex_;
  std::condition_variable ready_;
  std::deque<SweepRun> done_;
  size_t exited_ = 0;
  std::vector<std::thread> threads_;
};

int DefaultJobs(const SweepOptions& options) {
  if (options.jobs > 0) return options.jobs;
  if (options.mpi && options.mpi->size() > 1) return 1;
  return std::max(1u, std::thread::hardware_concurrency());
}

}  // namespace

KnotTracks SweepRun::Tracks() const {
  KnotTracks t;
  t.time = time;
  t.grid = grid;
  t.net = net;
  t.position = knots;
  t.valid.assign(knots.size(), 1);
  return t;
}

const char* StatusName(SweepRun::Status status) {
  switch (status) {
    case SweepRun::Status::kOk: return "ok";
    case SweepRun::Status::kBlewUp: return "blew up";
    case SweepRun::Status::kBadValue: return "bad value";
    case SweepRun::Status::kFailed: return "failed";
  }
  return "?";
}

int SweepResult::failed() const {
  return static_cast<int>(
      std::count_if(runs.begin(), runs.end(), [](const SweepRun& r) { return !r.ok(); }));
}

SweepRun RunOne(const std::string& scenario_path, int index,
                const std::vector<ScenarioOverride>& overrides, int decimate,
                const ProgressReporter& progress) {
  SweepRun run;
  run.index = index;
  run.overrides = overrides;
  try {
    const Scenario scenario = LoadScenario(scenario_path, overrides);
    RunOptions options;
    options.progress = progress;
    options.keep_every = decimate;
    // Net 0's corners, for the opening area.
    std::array<int, 4> corners = {-1, -1, -1, -1};
    options.on_built = [&](const BuiltScenario& built) {
      run.grid = built.knot_grid;
      run.net = built.knot_net;
      int rows = 0, cols = 0;
      for (size_t k = 0; k < built.knot_grid.size(); ++k)
        if (built.knot_net[k] == 0) {
          rows = std::max(rows, built.knot_grid[k][0] + 1);
          cols = std::max(cols, built.knot_grid[k][1] + 1);
        }
      const std::array<std::array<int, 2>, 4> want = {
          {{0, 0}, {0, cols - 1}, {rows - 1, cols - 1}, {rows - 1, 0}}};
      for (size_t k = 0; k < built.knot_grid.size(); ++k)
        for (int c = 0; c < 4; ++c)
          if (built.knot_net[k] == 0 && built.knot_grid[k] == want[c]) corners[c] = k;
    };
    int frame = 0;
    Vector3d first_centroid = Vector3d::Zero(), last_centroid = Vector3d::Zero();
    double max_area = -1.0;
    options.on_frame = [&](double time, const std::vector<Vector3d>& knots) {
      if (frame % decimate == 0) {
        run.time.push_back(time);
        run.knots.insert(run.knots.end(), knots.begin(), knots.end());
      }
      if (!knots.empty()) {
        Vector3d centroid = Vector3d::Zero();
        for (const Vector3d& k : knots) centroid += k;
        last_centroid = centroid / static_cast<double>(knots.size());
        if (frame == 0) first_centroid = last_centroid;
      }
      if (corners[0] >= 0 && corners[1] >= 0 && corners[2] >= 0 && corners[3] >= 0) {
        const double area = 0.5 * (knots[corners[2]] - knots[corners[0]])
                                      .cross(knots[corners[3]] - knots[corners[1]])
                                      .norm();
        if (area > max_area) {
          max_area = area;
          run.outputs.max_area_m2 = area;
          run.outputs.max_area_time_s = time;
        }
      }
      ++frame;
    };
    run.summary = RunScenario(scenario, options);
    run.summary.frames = frame;
    run.outputs.max_penetration_m = run.summary.max_penetration;
    if (frame > 0 && !run.grid.empty())
      run.outputs.centroid_drift_m = (last_centroid - first_centroid).norm();
    if (!run.summary.stable) {
      run.status = SweepRun::Status::kBlewUp;
      run.error = run.summary.error;
    }
  } catch (const Cancelled&) {
    throw;
  } catch (const InputError& e) {
    run.status = SweepRun::Status::kBadValue;
    run.error = e.what();
  } catch (const std::exception& e) {
    run.status = SweepRun::Status::kFailed;
    run.error = e.what();
  }
  return run;
}

SweepResult RunSweep(const std::string& scenario_path,
                     const std::vector<std::vector<ScenarioOverride>>& runs,
                     const SweepOptions& options) {
  if (options.decimate < 1) throw std::invalid_argument("RunSweep: decimate must be >= 1");
  const int total = static_cast<int>(runs.size());
  const MpiSession* mpi = options.mpi && options.mpi->size() > 1 ? options.mpi : nullptr;
  SweepResult result;
  result.jobs = DefaultJobs(options);
  result.ranks = mpi ? mpi->size() : 1;
  result.root = mpi == nullptr || mpi->rank() == 0;
  const auto start = Clock::now();
  const auto poll = std::chrono::milliseconds(mpi ? 1 : 100);

  if (!result.root) {
    // A rank other than 0: ask for one index per thread, run what comes, send each run back and
    // ask again, until rank 0 answers -1.
    std::mutex mutex;
    std::condition_variable cv;
    std::deque<int> queue;
    bool finished = false;
    Pool pool(
        scenario_path, runs, result.jobs, options.decimate, mpi->rank(),
        [&]() {
          std::unique_lock<std::mutex> lock(mutex);
          cv.wait(lock, [&] { return !queue.empty() || finished; });
          if (queue.empty()) return -1;
          const int i = queue.front();
          queue.pop_front();
          return i;
        },
        options.progress.cancel_token());
    int asked = 0, answered = 0, received = 0, sent = 0;
    for (int j = 0; j < result.jobs; ++j, ++asked) mpi->Send(0, kAsk, "");
    bool no_more = false;
    while (!(no_more && answered == asked && sent == received)) {
      if (options.progress.cancelled()) {
        std::lock_guard<std::mutex> lock(mutex);
        finished = true;
        cv.notify_all();
        throw Cancelled();
      }
      int from = 0, tag = 0;
      std::string bytes;
      while (mpi->Poll(&from, &tag, &bytes)) {
        if (tag != kIndex) continue;
        ++answered;
        const int i = BytesInt(bytes);
        std::lock_guard<std::mutex> lock(mutex);
        if (i < 0) {
          no_more = true;
        } else {
          ++received;
          queue.push_back(i);
        }
        cv.notify_all();
      }
      for (const SweepRun& run : pool.Take(poll)) {
        mpi->Send(0, kResult, Serialize(run));
        ++sent;
        if (!no_more) {
          mpi->Send(0, kAsk, "");
          ++asked;
        }
      }
    }
    {
      std::lock_guard<std::mutex> lock(mutex);
      finished = true;
      cv.notify_all();
    }
    mpi->Send(0, kBye, "");
    return result;
  }

  // Rank 0 (or the only process): its own threads and the other ranks take indices from `next`.
  std::atomic<int> next{0};
  auto take_index = [&]() {
    const int i = next.fetch_add(1);
    return i < total ? i : -1;
  };
  result.runs.resize(total);
  int done = 0, byes = 0;
  auto finish = [&](SweepRun&& run) {
    const int i = run.index;
    result.runs[i] = std::move(run);
    ++done;
    if (options.on_run) options.on_run(result.runs[i], done, total);
    if (!options.keep_tracks) {
      result.runs[i].time = {};
      result.runs[i].knots = {};
    }
  };
  {
    Pool pool(scenario_path, runs, result.jobs, options.decimate, 0, take_index,
              options.progress.cancel_token());
    auto last_progress = Clock::now();
    const int other_ranks = mpi ? mpi->size() - 1 : 0;
    // A callback that throws (e.g. the file cannot be written) ends the sweep: the threads
    // finish the runs they have and take no more.
    struct StopOnThrow {
      std::atomic<int>& next;
      int total;
      ~StopOnThrow() {
        if (std::uncaught_exceptions() > 0) next.store(total);
      }
    } stop{next, total};
    while (done < total || byes < other_ranks) {
      options.progress.ThrowIfCancelled();
      if (mpi) {
        int from = 0, tag = 0;
        std::string bytes;
        while (mpi->Poll(&from, &tag, &bytes)) {
          if (tag == kAsk) {
            mpi->Send(from, kIndex, IntBytes(take_index()));
          } else if (tag == kResult) {
            finish(Deserialize(bytes));
          } else if (tag == kBye) {
            ++byes;
          }
        }
      }
      for (SweepRun& run : pool.Take(poll)) finish(std::move(run));
      if (Clock::now() - last_progress > std::chrono::milliseconds(200)) {
        last_progress = Clock::now();
        options.progress.Report("runs", done + pool.UnderWay(), total);
      }
      if (!mpi && pool.Exited() && done < total) {
        options.progress.ThrowIfCancelled();  // the threads stopped for the cancel
        throw std::logic_error("RunSweep: the pool ended with runs missing");
      }
    }
  }
  result.wall_s = std::chrono::duration<double>(Clock::now() - start).count();
  return result;
}

}  // namespace netlab::netsim
