// netlab ingest EXPERIMENT.yaml --check [--decode] [--json]
// netlab ingest EXPERIMENT.yaml --to-hdf5 OUT.h5 [--compress N] [--json]

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <iostream>
#include <thread>

#include "app/cli/commands.h"
#include "app/cli/json_writer.h"
#include "app/cli/progress_bar.h"
#include "app/command_line/command_line.h"
#include "common/files.h"
#include "common/output_paths.h"
#include "libreconstruct/recording/frame_store.h"
#include "libreconstruct/recording/sequence.h"

namespace netlab::app {
namespace {

constexpr char kHelp[] =
    "usage: netlab ingest EXPERIMENT.yaml --check [--decode] [--json]\n"
    "       netlab ingest EXPERIMENT.yaml --to-hdf5 OUT.h5 [--compress N] [--json]\n\n"
    "Reads the synchronized camera recordings an experiment file lists (docs/ingest.md).\n\n"
    "  --check        read every frame's header; report per camera the frames, size, missing\n"
    "                 and unreadable frame indices, and the synchronized frames of all cameras\n"
    "  --decode       with --check: read and demosaic every frame (finds corrupt data and\n"
    "                 duplicated frames; decode_fps is then measured on all of them)\n"
    "  --to-hdf5 FILE convert the recording into the HDF5 frame store FILE (one chunked dataset\n"
    "                 per camera, written via FILE.partial) and write the experiment file that\n"
    "                 reads it next to it (FILE with .yaml for .h5)\n"
    "  --compress N   gzip level 1..9 for --to-hdf5 (default 0: none, fastest to read)\n"
    "  --threads N    decoding threads (default 2)\n"
    "  --json         print one JSON summary object on stdout as the last output\n"
    "  --quiet        no report or progress on stderr\n\n"
    "exit status: 0 read (gaps and unreadable frames are reported, not fatal), 1 bad experiment\n"
    "file, missing recording or no readable frame, 2 usage error.\n";

// Camera frames decoded and demosaiced per second on `threads` threads, measured on up to
// `samples` frame indices per camera spread over the recording (the header-only check reads no
// pixels, so this is what tells a user how fast the recording plays).
double SampleDecodeFps(const recon::SynchronizedSequence& sequence, int threads, int samples) {
  std::vector<std::pair<int, int>> tasks;
  for (int c = 0; c < sequence.num_cameras(); ++c) {
    const std::vector<int>& idx = sequence.source(c).indices();
    const int n = std::min<int>(samples, static_cast<int>(idx.size()));
    for (int k = 0; k < n; ++k)
      tasks.emplace_back(c, idx[(idx.size() - 1) * k / std::max(1, n - 1)]);
  }
  std::atomic<int> next{0}, decoded{0};
  const auto start = std::chrono::steady_clock::now();
  auto worker = [&] {
    std::string error;
    for (int t; (t = next++) < static_cast<int>(tasks.size());)
      if (!sequence.ReadDisplay(tasks[t].first, tasks[t].second, 0, &error).empty()) ++decoded;
  };
  std::vector<std::thread> pool;
  for (int t = 1; t < threads; ++t) pool.emplace_back(worker);
  worker();
  for (std::thread& t : pool) t.join();
  const double wall =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return wall > 0 ? decoded / wall : 0.0;
}

void WriteIndices(JsonWriter& json, const std::string& key, const std::vector<int>& indices) {
  json.Key(key).BeginArray();
  for (int i : indices) json.Int(i);
  json.EndArray();
}

struct Conversion {
  std::string output, experiment_file;
  int frames = 0;
  uintmax_t bytes = 0;
  double wall_s = 0.0;
};

void PrintJson(const recon::SynchronizedSequence& sequence, const recon::CheckReport* check,
               double decode_fps, bool decode_sampled, const Conversion* conversion) {
  JsonWriter json;
  json.BeginObject();
  json.Key("experiment").String(sequence.experiment().name);
  json.Key("fps").Number(sequence.experiment().fps);
  json.Key("first_frame").Int(sequence.first_frame());
  json.Key("last_frame").Int(sequence.last_frame());
  if (check) {
    json.Key("cameras").BeginArray();
    for (const recon::CameraReport& c : check->cameras) {
      json.BeginObject();
      json.Key("name").String(c.name);
      json.Key("frames").Int(c.frames);
      json.Key("width").Int(c.width);
      json.Key("height").Int(c.height);
      json.Key("bit_depth").Int(sequence.Correction(sequence.experiment().Find(c.name)).bit_depth);
      WriteIndices(json, "missing", c.missing);
      WriteIndices(json, "unreadable", c.unreadable);
      WriteIndices(json, "duplicated", c.duplicated);
      WriteIndices(json, "timestamp_gaps", c.timestamp_gaps);
      WriteIndices(json, "untimed", c.untimed);
      json.Key("problems").BeginArray();
      for (const std::string& p : c.problems) json.String(p);
      json.EndArray();
      json.EndObject();
    }
    json.EndArray();
    json.Key("synchronized_frames").Int(check->synchronized_frames);
    json.Key("decoded").Bool(check->decoded);
    json.Key("decode_fps").Number(decode_fps);
    json.Key("decode_fps_sampled").Bool(decode_sampled);
    json.Key("synchronized_fps").Number(decode_fps / std::max(1, sequence.num_cameras()));
    json.Key("check_wall_s").Number(check->wall_s);
    json.Key("warnings").BeginArray();
    for (const std::string& w : check->warnings) json.String(w);
    json.EndArray();
  }
  if (conversion) {
    json.Key("hdf5").BeginObject();
    json.Key("output").String(conversion->output);
    json.Key("experiment_file").String(conversion->experiment_file);
    json.Key("frames").Int(conversion->frames);
    json.Key("bytes").Int(static_cast<long long>(conversion->bytes));
    json.Key("wall_s").Number(conversion->wall_s);
    json.EndObject();
  }
  json.EndObject();
  std::cout << json.str() << std::endl;
}

}  // namespace

int RunIngest(const std::vector<std::string>& args) {
  return RunGuarded("ingest", [&] {
    const CommandLine cl(args, {"check", "decode", "json", "quiet", "help"},
                         {"to-hdf5", "compress", "threads"});
    if (cl.Flag("help")) {
      std::fputs(kHelp, stdout);
      return 0;
    }
    if (cl.positional().size() != 1)
      throw UsageError(cl.positional().empty()
                           ? "EXPERIMENT.yaml is required"
                           : "unexpected argument '" + cl.positional()[1] + "'");
    const auto to_hdf5 = cl.Option("to-hdf5");
    if (!cl.Flag("check") && !to_hdf5) throw UsageError("say --check or --to-hdf5 OUT.h5");
    if (cl.Flag("decode") && !cl.Flag("check")) throw UsageError("--decode goes with --check");
    if (cl.Option("compress") && !to_hdf5) throw UsageError("--compress goes with --to-hdf5");
    const int compress = cl.IntOption("compress", 0, 0, 9);
    const int threads = cl.IntOption("threads", 2, 1, 64);
    const bool quiet = cl.Flag("quiet");

    recon::Experiment experiment = recon::LoadExperiment(cl.positional()[0]);
    if (to_hdf5) {
      // Before any work: neither the store nor its experiment file over an input (the experiment
      // file, a camera's video, store or timestamps) or over each other.
      std::vector<NamedPath> inputs = {{"experiment", cl.positional()[0]}};
      for (const auto& [what, path] : recon::RecordingFiles(experiment))
        inputs.push_back({what, path});
      CheckOutputPaths(inputs, {{"--to-hdf5", *to_hdf5},
                                {"--to-hdf5 (the experiment file written beside it)",
                                 recon::FrameStoreExperimentPath(*to_hdf5)}});
    }
    const recon::SynchronizedSequence sequence(std::move(experiment));
    recon::CheckReport check;
    double decode_fps = 0.0;
    bool sampled = false;
    if (cl.Flag("check")) {
      const bool decode = cl.Flag("decode");
      ProgressBar bar("ingest", !quiet);
      check = sequence.Check(decode, bar.Reporter(), threads);
      bar.Break();
      if (decode) {
        decode_fps = check.read_fps;
      } else {
        decode_fps = SampleDecodeFps(sequence, threads, 8);
        sampled = true;
      }
      if (!quiet) std::cerr << check.BriefReport();
      if (check.synchronized_frames == 0 && !quiet)
        std::cerr << "warning: no frame index is readable in every camera\n";
    }

    Conversion conversion;
    if (to_hdf5) {
      const auto start = std::chrono::steady_clock::now();
      ProgressBar bar("ingest", !quiet);
      // The store and its experiment file put in place together once both are complete.
      OutputSet outputs({*to_hdf5, recon::FrameStoreExperimentPath(*to_hdf5)});
      const recon::Experiment stored =
          recon::ConvertToFrameStore(sequence, *to_hdf5, {compress}, bar.Reporter());
      bar.Break();
      recon::WriteExperiment(stored.path, stored);
      outputs.Commit();
      conversion.output = *to_hdf5;
      conversion.experiment_file = stored.path;
      conversion.frames = sequence.last_frame() - sequence.first_frame() + 1;
      conversion.bytes = std::filesystem::file_size(*to_hdf5);
      conversion.wall_s =
          std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      if (!quiet)
        std::fprintf(stderr,
                     "frame store %s (%.1f MB, %d frames per camera, %.1f s); read it with %s\n",
                     to_hdf5->c_str(), conversion.bytes / 1e6, conversion.frames, conversion.wall_s,
                     stored.path.c_str());
    }
    if (cl.Flag("json"))
      PrintJson(sequence, cl.Flag("check") ? &check : nullptr, decode_fps, sampled,
                to_hdf5 ? &conversion : nullptr);
    return 0;
  });
}

}  // namespace netlab::app
