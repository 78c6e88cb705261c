#include "libreconstruct/recording/frame_source.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <opencv2/core/utils/logger.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/videoio.hpp>
#include <opencv2/videoio/registry.hpp>
#include <regex>

#include "common/errors.h"
#include "common/hdf5_util.h"

namespace netlab::recon {
namespace {

namespace fs = std::filesystem;

std::string Resolve(const std::string& base_dir, const std::string& path) {
  const fs::path p(path);
  if (p.is_absolute() || base_dir.empty()) return path;
  return (fs::path(base_dir) / p).string();
}

std::string Lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), ::tolower);
  return s;
}

// Skips whitespace and '#' comments of a PNM header.
size_t SkipSpace(const std::string& b, size_t i) {
  while (i < b.size()) {
    if (b[i] == '#') {
      while (i < b.size() && b[i] != '\n') ++i;
    } else if (std::isspace(static_cast<unsigned char>(b[i]))) {
      ++i;
    } else {
      break;
    }
  }
  return i;
}

bool ParseNumber(const std::string& b, size_t* i, int* value) {
  *i = SkipSpace(b, *i);
  size_t start = *i;
  while (*i < b.size() && std::isdigit(static_cast<unsigned char>(b[*i]))) ++*i;
  if (*i == start || *i - start > 9) return false;
  *value = std::stoi(b.substr(start, *i - start));
  return true;
}

// Parses a P5 header from the first bytes; sets the data offset.
bool ParsePgmHeader(const std::string& head, FrameInfo* info, size_t* data_offset, int* maxval,
                    std::string* error) {
  if (head.size() < 2 || head[0] != 'P' || head[1] != '5') {
    *error = "not a binary PGM (P5) file";
    return false;
  }
  size_t i = 2;
  int w, h, m;
  if (!ParseNumber(head, &i, &w) || !ParseNumber(head, &i, &h) || !ParseNumber(head, &i, &m) ||
      w <= 0 || h <= 0 || m <= 0 || m > 65535 || i >= head.size()) {
    *error = "corrupt PGM header";
    return false;
  }
  *data_offset = i + 1;  // one whitespace character after maxval
  *maxval = m;
  info->width = w;
  info->height = h;
  info->depth = m > 255 ? CV_16U : CV_8U;
  info->channels = 1;
  return true;
}

// The image format a file's first bytes say ("PNM", "PNG", "TIFF", "JPEG", "BMP"), or "" when
// they say none of these.
std::string FormatOfContent(const std::string& head) {
  const auto starts = [&](const char* magic, size_t n) {
    return head.compare(0, n, magic, n) == 0;
  };
  if (head.size() >= 2 && head[0] == 'P' && head[1] >= '1' && head[1] <= '6') return "PNM";
  if (starts("\x89PNG", 4)) return "PNG";
  if (starts("II*\0", 4) || starts("MM\0*", 4)) return "TIFF";
  if (starts("\xFF\xD8\xFF", 3)) return "JPEG";
  if (starts("BM", 2)) return "BMP";
  return "";
}

// The format a file name's extension promises, or "" for another extension.
std::string FormatOfName(const std::string& path) {
  const std::string ext = Lower(fs::path(path).extension().string());
  if (ext == ".pgm" || ext == ".pnm" || ext == ".ppm") return "PNM";
  if (ext == ".png") return "PNG";
  if (ext == ".tif" || ext == ".tiff") return "TIFF";
  if (ext == ".jpg" || ext == ".jpeg") return "JPEG";
  if (ext == ".bmp") return "BMP";
  return "";
}

// The one rule for a frame file, header check and decoding alike: a file's content must be the
// format its name says (a PNG renamed .pgm would pass a check by content and then fail to decode
// by name, or the other way round). "" when it is, else e.g. "a PNG file named .pgm".
std::string NameMismatch(const std::string& path, const std::string& head) {
  const std::string named = FormatOfName(path), content = FormatOfContent(head);
  if (named.empty() || content.empty() || named == content) return "";
  return "a " + content + " file named " + fs::path(path).extension().string();
}

// The first bytes of a file (up to 512) and its size; false when it cannot be opened.
bool ReadHead(const std::string& path, std::string* head, std::streamsize* size) {
  std::ifstream in(path, std::ios::binary | std::ios::ate);
  if (!in) return false;
  *size = in.tellg();
  in.seekg(0);
  head->assign(static_cast<size_t>(std::min<std::streamsize>(*size, 512)), '\0');
  in.read(head->data(), static_cast<std::streamsize>(head->size()));
  return true;
}

uint32_t BigEndian32(const unsigned char* p) {
  return (uint32_t(p[0]) << 24) | (uint32_t(p[1]) << 16) | (uint32_t(p[2]) << 8) | p[3];
}

class ImageSequenceSource final : public FrameSource {
 public:
  ImageSequenceSource(std::string pattern, std::string spec)
      : pattern_(std::move(pattern)), spec_(std::move(spec)) {
    SilenceOpenCvLogging();
    const size_t percent = pattern_.find('%');
    const fs::path dir = fs::path(pattern_).parent_path();
    const std::string name = fs::path(pattern_).filename().string();
    const size_t p = name.find('%');
    const std::regex spec_re("%(0?)([0-9]*)d");
    std::smatch m;
    // A '%' only in a folder name leaves no pattern in the file name (and nothing to substr).
    const std::string rest = p == std::string::npos ? std::string() : name.substr(p);
    if (percent == std::string::npos || p == std::string::npos ||
        !std::regex_search(rest, m, spec_re) || m.position(0) != 0)
      throw InputError(spec_ + ": expected a printf pattern with %d (e.g. frame_%06d.pgm)");
    const std::string prefix = name.substr(0, p), suffix = rest.substr(m.length(0));
    if (suffix.find('%') != std::string::npos)
      throw InputError(spec_ + ": only one %d is allowed in a frame pattern");
    if (!fs::is_directory(dir.empty() ? fs::path(".") : dir))
      throw InputError(spec_ + ": folder " + dir.string() + " does not exist");
    for (const auto& entry : fs::directory_iterator(dir.empty() ? fs::path(".") : dir)) {
      const std::string file = entry.path().filename().string();
      if (file.size() <= prefix.size() + suffix.size() || file.compare(0, prefix.size(), prefix) ||
          file.compare(file.size() - suffix.size(), suffix.size(), suffix))
        continue;
      const std::string digits =
          file.substr(prefix.size(), file.size() - prefix.size() - suffix.size());
      if (digits.empty() || digits.size() > 9 ||
          !std::all_of(digits.begin(), digits.end(), ::isdigit))
        continue;
      const int index = std::stoi(digits);
      if (Path(index) != entry.path().string() && fs::path(Path(index)).filename() != file)
        continue;
      indices_.push_back(index);
    }
    std::sort(indices_.begin(), indices_.end());
    if (indices_.empty()) throw InputError(spec_ + ": the pattern matches no file");
    extension_ = Lower(fs::path(pattern_).extension().string());
  }

  std::string Describe() const override { return spec_; }
  const std::vector<int>& indices() const override { return indices_; }
  std::string Where(int index) const override { return Path(index); }

  bool Header(int index, FrameInfo* info, std::string* error) const override {
    return ReadImageHeader(Path(index), info, error);
  }

  cv::Mat Read(int index, std::string* error) const override {
    const std::string path = Path(index);
    if (extension_ == ".pgm" || extension_ == ".pnm") return ReadPgm(path, error);
    std::string head;
    std::streamsize size = 0;
    if (!ReadHead(path, &head, &size)) {
      *error = "cannot open file";
      return {};
    }
    if (const std::string mismatch = NameMismatch(path, head); !mismatch.empty()) {
      *error = mismatch;
      return {};
    }
    cv::Mat image = cv::imread(path, cv::IMREAD_UNCHANGED);
    if (image.empty()) *error = size == 0 ? "empty file" : "cannot decode image";
    return image;
  }

 private:
  std::string Path(int index) const {
    char buffer[4096];
    std::snprintf(buffer, sizeof(buffer), pattern_.c_str(), index);
    return buffer;
  }

  std::string pattern_, spec_, extension_;
  std::vector<int> indices_;
};

class VideoSource final : public FrameSource {
 public:
  VideoSource(std::string path, std::string spec) : path_(std::move(path)), spec_(std::move(spec)) {
    if (!fs::exists(path_)) throw InputError(spec_ + ": video file not found");
    OpenVideo();
    const int count = static_cast<int>(capture_.get(cv::CAP_PROP_FRAME_COUNT));
    for (int i = 0; i < count; ++i) indices_.push_back(i);
    info_.width = static_cast<int>(capture_.get(cv::CAP_PROP_FRAME_WIDTH));
    info_.height = static_cast<int>(capture_.get(cv::CAP_PROP_FRAME_HEIGHT));
    info_.depth = CV_8U;
    info_.channels = 3;
    if (indices_.empty()) throw InputError(spec_ + ": the video has no frames");
  }
  std::string Describe() const override { return spec_; }
  const std::vector<int>& indices() const override { return indices_; }
  std::string Where(int index) const override { return path_ + "[" + std::to_string(index) + "]"; }

  // Opens the video quietly, so that netlab's message is the only one: OpenCV's logging off, and
  // FFmpeg named as the backend when OpenCV has it (tried first by default, GStreamer prints
  // "pipeline have not been created" and an assertion for any file it cannot open). An empty
  // file is refused before any backend sees it.
  void OpenVideo() {
    SilenceOpenCvLogging();
    std::error_code error;
    if (fs::file_size(path_, error) == 0 && !error)
      throw InputError(spec_ + ": empty file (0 bytes), not a video");
    const int backend =
        cv::videoio_registry::hasBackend(cv::CAP_FFMPEG) ? cv::CAP_FFMPEG : cv::CAP_ANY;
    bool opened = false;
    try {
      opened = capture_.open(path_, backend);
    } catch (const cv::Exception&) {
      opened = false;
    }
    if (!opened)
      throw InputError(spec_ + ": cannot open as a video (" +
                       (backend == cv::CAP_FFMPEG ? "FFmpeg" : "OpenCV") +
                       " reads no video stream from it)");
  }
  bool Header(int index, FrameInfo* info, std::string* error) const override {
    if (index < 0 || index >= static_cast<int>(indices_.size())) {
      *error = "no such frame";
      return false;
    }
    *info = info_;
    return true;
  }
  cv::Mat Read(int index, std::string* error) const override {
    std::lock_guard<std::mutex> lock(mutex_);
    if (index != next_) capture_.set(cv::CAP_PROP_POS_FRAMES, index);
    cv::Mat frame;
    if (!capture_.read(frame) || frame.empty()) {
      *error = "cannot decode video frame";
      next_ = -1;
      return {};
    }
    next_ = index + 1;
    return frame;
  }

 private:
  std::string path_, spec_;
  std::vector<int> indices_;
  FrameInfo info_;
  mutable std::mutex mutex_;
  mutable cv::VideoCapture capture_;
  mutable int next_ = 0;
};

class Hdf5FrameSource final : public FrameSource {
 public:
  Hdf5FrameSource(std::string file, std::string dataset, std::string spec)
      : file_path_(std::move(file)), dataset_path_(std::move(dataset)), spec_(std::move(spec)) {
    std::lock_guard<std::mutex> lock(h5::Mutex());
    try {
      file_ = h5::OpenFileReadOnly(file_path_);
    } catch (const std::exception& e) {
      throw InputError(spec_ + ": " + e.what());
    }
    if (!h5::Exists(file_.get(), dataset_path_))
      throw InputError(spec_ + ": no dataset " + dataset_path_ + " in " + file_path_);
    dataset_ = h5::Id(H5Dopen2(file_.get(), dataset_path_.c_str(), H5P_DEFAULT));
    dims_ = h5::DatasetDims(file_.get(), dataset_path_);
    if (dims_.size() != 3 && !(dims_.size() == 4 && dims_[3] == 3))
      throw InputError(spec_ + ": expected a dataset [T, H, W] or [T, H, W, 3]");
    h5::Id type(H5Dget_type(dataset_.get()));
    const size_t size = H5Tget_size(type.get());
    if (size != 1 && size != 2) throw InputError(spec_ + ": frames must be 8 or 16 bit integers");
    info_.height = static_cast<int>(dims_[1]);
    info_.width = static_cast<int>(dims_[2]);
    info_.depth = size == 1 ? CV_8U : CV_16U;
    info_.channels = dims_.size() == 4 ? 3 : 1;
    int first = 0;
    const std::string first_text = h5::ReadStringAttribute(dataset_.get(), "first_index");
    try {
      if (!first_text.empty()) first = std::stoi(first_text);
    } catch (const std::exception&) {
      throw InputError(spec_ + ": attribute first_index is not an integer: '" + first_text + "'");
    }
    std::vector<uint8_t> valid(dims_[0], 1);
    if (HasPerFrame("_valid"))
      h5::ReadDataset(file_.get(), dataset_path_ + "_valid", H5T_NATIVE_UINT8, valid.data());
    for (hsize_t t = 0; t < dims_[0]; ++t)
      if (valid[t]) indices_.push_back(first + static_cast<int>(t));
    first_ = first;
    if (indices_.empty()) throw InputError(spec_ + ": the dataset holds no frames");
    const std::string times = dataset_path_ + "_timestamps";
    if (HasPerFrame("_timestamps")) {
      std::vector<double> t(dims_[0]);
      h5::ReadDataset(file_.get(), times, H5T_NATIVE_DOUBLE, t.data());
      // In seconds: a unit the file states is converted (ms, us, ns) or refused.
      const double to_s = h5::UnitsFactor(file_.get(), file_path_, times, h5::kSeconds);
      for (double& time : t) time *= to_s;
      for (int index : indices_)
        if (std::isfinite(t[index - first])) timestamps_[index] = t[index - first];
    }
  }
  std::map<int, double> Timestamps() const override { return timestamps_; }

  // Whether the store has the per-frame dataset <dataset><suffix> (_valid, _timestamps); a
  // length other than the frames' is an InputError naming both, not ignored: a short _valid
  // silently dropped would count its gaps' zeros as frames.
  bool HasPerFrame(const std::string& suffix) const {
    const std::string path = dataset_path_ + suffix;
    if (!h5::Exists(file_.get(), path)) return false;
    const std::vector<hsize_t> dims = h5::DatasetDims(file_.get(), path);
    if (dims == std::vector<hsize_t>{dims_[0]}) return true;
    std::string shape;
    for (size_t i = 0; i < dims.size(); ++i) shape += (i ? " x " : "") + std::to_string(dims[i]);
    throw InputError(
        file_path_ + ":" + path + " has " +
        (dims.size() == 1 ? std::to_string(dims[0]) + " entries" : "shape [" + shape + "]") + ", " +
        dataset_path_ + " has " + std::to_string(dims_[0]) +
        " frames (one entry per frame expected)");
  }

  ~Hdf5FrameSource() override {
    std::lock_guard<std::mutex> lock(h5::Mutex());
    dataset_.Reset();
    file_.Reset();
  }
  std::string Describe() const override { return spec_; }
  const std::vector<int>& indices() const override { return indices_; }
  std::string Where(int index) const override {
    return file_path_ + ":" + dataset_path_ + "[" + std::to_string(index - first_) + "]";
  }
  bool Header(int index, FrameInfo* info, std::string* error) const override {
    if (!std::binary_search(indices_.begin(), indices_.end(), index)) {
      *error = "no such frame";
      return false;
    }
    *info = info_;
    return true;
  }
  cv::Mat Read(int index, std::string* error) const override {
    // Not only the dataset's range: a gap (valid 0) holds zeros, not a frame.
    const int t = index - first_;
    if (!std::binary_search(indices_.begin(), indices_.end(), index)) {
      *error = "no such frame";
      return {};
    }
    cv::Mat frame(info_.height, info_.width, CV_MAKETYPE(info_.depth, info_.channels));
    std::lock_guard<std::mutex> lock(h5::Mutex());
    try {
      h5::ReadFrame(dataset_.get(), info_.depth == CV_8U ? H5T_NATIVE_UINT8 : H5T_NATIVE_UINT16, t,
                    frame.data);
    } catch (const std::exception& e) {
      *error = e.what();
      return {};
    }
    return frame;
  }

 private:
  std::string file_path_, dataset_path_, spec_;
  h5::Id file_, dataset_;
  std::vector<hsize_t> dims_;
  FrameInfo info_;
  std::vector<int> indices_;
  std::map<int, double> timestamps_;
  int first_ = 0;
};

}  // namespace

void SilenceOpenCvLogging() {
  static std::once_flag once;
  std::call_once(once,
                 [] { cv::utils::logging::setLogLevel(cv::utils::logging::LOG_LEVEL_SILENT); });
}

cv::Mat ReadPgm(const std::string& path, std::string* error) {
  std::ifstream in(path, std::ios::binary | std::ios::ate);
  if (!in) {
    *error = "cannot open file";
    return {};
  }
  const std::streamsize size = in.tellg();
  in.seekg(0);
  std::string head(std::min<std::streamsize>(size, 512), '\0');
  in.read(head.data(), static_cast<std::streamsize>(head.size()));
  if (size == 0) {
    *error = "empty file";
    return {};
  }
  if (const std::string mismatch = NameMismatch(path, head); !mismatch.empty()) {
    *error = mismatch;
    return {};
  }
  FrameInfo info;
  size_t offset;
  int maxval;
  if (!ParsePgmHeader(head, &info, &offset, &maxval, error)) return {};
  const size_t bytes =
      static_cast<size_t>(info.width) * info.height * (info.depth == CV_16U ? 2 : 1);
  if (static_cast<size_t>(size) < offset + bytes) {
    *error = "truncated: " + std::to_string(size - static_cast<std::streamsize>(offset)) + " of " +
             std::to_string(bytes) + " data bytes";
    return {};
  }
  cv::Mat frame(info.height, info.width, CV_MAKETYPE(info.depth, 1));
  in.seekg(static_cast<std::streamoff>(offset));
  in.read(reinterpret_cast<char*>(frame.data), static_cast<std::streamsize>(bytes));
  if (!in) {
    *error = "read error";
    return {};
  }
  if (info.depth == CV_16U) {
    // PGM stores 16-bit samples big-endian.
    uint16_t* p = frame.ptr<uint16_t>();
    const size_t n = frame.total();
    for (size_t i = 0; i < n; ++i) p[i] = static_cast<uint16_t>((p[i] << 8) | (p[i] >> 8));
  }
  return frame;
}

bool ReadImageHeader(const std::string& path, FrameInfo* info, std::string* error) {
  std::string head;
  std::streamsize size = 0;
  if (!ReadHead(path, &head, &size)) {
    *error = "cannot open file";
    return false;
  }
  if (size == 0) {
    *error = "empty file";
    return false;
  }
  if (const std::string mismatch = NameMismatch(path, head); !mismatch.empty()) {
    *error = mismatch;
    return false;
  }
  // A .pgm must be a binary PGM (ReadPgm reads nothing else), whatever cv::imread could decode.
  if (FormatOfName(path) == "PNM" || (head.size() >= 2 && head[0] == 'P' && head[1] == '5')) {
    size_t offset;
    int maxval;
    if (!ParsePgmHeader(head, info, &offset, &maxval, error)) return false;
    const size_t bytes =
        static_cast<size_t>(info->width) * info->height * (info->depth == CV_16U ? 2 : 1);
    if (static_cast<size_t>(size) < offset + bytes) {
      *error = "truncated: " + std::to_string(size - static_cast<std::streamsize>(offset)) +
               " of " + std::to_string(bytes) + " data bytes";
      return false;
    }
    return true;
  }
  const unsigned char* u = reinterpret_cast<const unsigned char*>(head.data());
  if (head.size() >= 26 && head.compare(1, 3, "PNG") == 0 && head.compare(12, 4, "IHDR") == 0) {
    info->width = static_cast<int>(BigEndian32(u + 16));
    info->height = static_cast<int>(BigEndian32(u + 20));
    info->depth = u[24] == 16 ? CV_16U : CV_8U;
    const int color = u[25];
    info->channels = color == 0 || color == 4 ? 1 : 3;
    if (info->width <= 0 || info->height <= 0) {
      *error = "corrupt PNG header";
      return false;
    }
    return true;
  }
  // Other formats: decode to learn the size.
  const cv::Mat image = cv::imread(path, cv::IMREAD_UNCHANGED);
  if (image.empty()) {
    *error = "cannot decode image";
    return false;
  }
  info->width = image.cols;
  info->height = image.rows;
  info->depth = image.depth() == CV_16U ? CV_16U : CV_8U;
  info->channels = image.channels() >= 3 ? 3 : 1;
  return true;
}

std::unique_ptr<FrameSource> OpenFrameSource(const std::string& spec, const std::string& base_dir) {
  // "file.h5:/dataset"
  const size_t colon = spec.find(".h5:");
  if (colon != std::string::npos) {
    const std::string file = Resolve(base_dir, spec.substr(0, colon + 3));
    return std::make_unique<Hdf5FrameSource>(file, spec.substr(colon + 4), spec);
  }
  const std::string path = Resolve(base_dir, spec);
  if (spec.find('%') != std::string::npos) return std::make_unique<ImageSequenceSource>(path, spec);
  return std::make_unique<VideoSource>(path, spec);
}

}  // namespace netlab::recon
