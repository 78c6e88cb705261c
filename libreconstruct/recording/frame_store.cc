#include "libreconstruct/recording/frame_store.h"

#include <cmath>
#include <filesystem>
#include <limits>
#include <mutex>
#include <stdexcept>

#include "common/files.h"
#include "common/hdf5_util.h"

namespace netlab::recon {

std::string FrameStoreExperimentPath(const std::string& path) {
  const bool h5 = path.size() > 3 && path.substr(path.size() - 3) == ".h5";
  return path.substr(0, path.size() - (h5 ? 3 : 0)) + ".yaml";
}

std::vector<std::pair<std::string, std::string>> RecordingFiles(const Experiment& experiment) {
  namespace fs = std::filesystem;
  auto resolve = [&](const std::string& path) {
    return fs::path(path).is_absolute() || experiment.base_dir.empty()
               ? path
               : (fs::path(experiment.base_dir) / path).string();
  };
  std::vector<std::pair<std::string, std::string>> files;
  for (const CameraSpec& c : experiment.cameras) {
    // As OpenFrameSource reads the spec: "file.h5:/dataset", an image pattern, or a video.
    const size_t colon = c.frames.find(".h5:");
    if (colon != std::string::npos)
      files.emplace_back(c.name + " frames", resolve(c.frames.substr(0, colon + 3)));
    else if (c.frames.find('%') == std::string::npos)
      files.emplace_back(c.name + " frames", resolve(c.frames));
    if (!c.timestamps.empty()) files.emplace_back(c.name + " timestamps", c.timestamps);
  }
  return files;
}

Experiment ConvertToFrameStore(const SynchronizedSequence& sequence, const std::string& path,
                               const FrameStoreOptions& options, const ProgressReporter& progress) {
  const Experiment& in = sequence.experiment();
  const int first = sequence.first_frame(), count = sequence.last_frame() - first + 1;
  const std::string partial = path + ".partial";
  Experiment out = in;
  out.path = FrameStoreExperimentPath(path);
  out.base_dir = std::filesystem::path(path).parent_path().string();
  const std::string file_name = std::filesystem::path(path).filename().string();
  const int total = count * sequence.num_cameras();
  int done = 0;
  try {
    // HDF5 calls hold the library lock; reading a source does not (an HDF5 source takes the lock
    // itself: converting one store into another must not deadlock).
    std::unique_lock<std::mutex> lock(h5::Mutex());
    h5::Id file = h5::CreateFile(partial);
    h5::WriteStringAttribute(file.get(), "format", "netlab-frame-store");
    h5::WriteStringAttribute(file.get(), "experiment", in.name);
    for (int c = 0; c < sequence.num_cameras(); ++c) {
      const CameraSpec& spec = in.cameras[c];
      const FrameSource& source = sequence.source(c);
      // The camera's frame layout: its first readable header.
      FrameInfo info;
      std::string error;
      bool found = false;
      lock.unlock();
      for (int i : source.indices())
        if ((found = source.Header(i, &info, &error))) break;
      const std::map<int, double> timestamps =
          spec.timestamps.empty() ? source.Timestamps() : ReadTimestamps(spec.timestamps);
      lock.lock();
      if (!found) throw std::runtime_error(spec.name + ": no readable frame to convert");
      std::vector<hsize_t> frame_dims = {static_cast<hsize_t>(info.height),
                                         static_cast<hsize_t>(info.width)};
      if (info.channels == 3) frame_dims.push_back(3);
      const hid_t type = info.depth == CV_16U ? H5T_NATIVE_UINT16 : H5T_NATIVE_UINT8;
      h5::Id data =
          h5::CreateFrameDataset(file.get(), spec.name, type, frame_dims, 1, options.deflate_level);
      h5::WriteStringAttribute(data.get(), "bayer", BayerPatternName(spec.bayer));
      h5::WriteStringAttribute(data.get(), "bit_depth",
                               std::to_string(sequence.Correction(c).bit_depth));
      h5::WriteStringAttribute(data.get(), "first_index", std::to_string(first));
      h5::WriteStringAttribute(data.get(), "fps", std::to_string(in.fps));
      std::vector<uint8_t> valid(count, 0);
      std::vector<double> times(count, std::numeric_limits<double>::quiet_NaN());
      const cv::Mat blank(info.height, info.width, CV_MAKETYPE(info.depth, info.channels),
                          cv::Scalar::all(0));
      for (int t = 0; t < count; ++t) {
        const int index = first + t;
        cv::Mat frame;
        lock.unlock();
        if (sequence.Has(c, index)) {
          frame = source.Read(index, &error);
          if (!frame.empty() && (frame.cols != info.width || frame.rows != info.height ||
                                 frame.depth() != info.depth || frame.channels() != info.channels))
            frame.release();  // a frame of another size or type: unreadable here
        }
        if (!frame.empty() && !frame.isContinuous()) frame = frame.clone();
        lock.lock();
        valid[t] = !frame.empty();
        h5::AppendFrame(data.get(), type, (frame.empty() ? blank : frame).data, t);
        if (const auto it = timestamps.find(index); it != timestamps.end()) times[t] = it->second;
        progress.Report("frames converted", ++done, total);
        progress.ThrowIfCancelled();
      }
      h5::WriteDataset(file.get(), spec.name + "_valid", H5T_NATIVE_UINT8,
                       {static_cast<hsize_t>(count)}, valid.data());
      h5::WriteDataset(file.get(), spec.name + "_timestamps", H5T_NATIVE_DOUBLE,
                       {static_cast<hsize_t>(count)}, times.data());
      h5::SetUnits(file.get(), spec.name + "_timestamps", "s");
      out.cameras[c].frames = file_name + ":/" + spec.name;
      out.cameras[c].timestamps.clear();
      out.cameras[c].bit_depth = sequence.Correction(c).bit_depth;
    }
    H5Fflush(file.get(), H5F_SCOPE_GLOBAL);
  } catch (...) {
    std::error_code ignored;
    std::filesystem::remove(partial, ignored);  // no half-written store is left behind
    throw;
  }
  RenameInto(partial, path);
  return out;
}

}  // namespace netlab::recon
