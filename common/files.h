#pragma once
// Replacing a file or a folder safely: everything netlab writes goes to "<path>.partial" first and
// is renamed into place when complete, so an interrupted or failing write never destroys what the
// user had and never leaves a half-written output under the output's name.

#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <stdexcept>
#include <string>
#include <system_error>
#include <vector>

namespace netlab {

namespace files_internal {

// The outputs an OutputSet holds back: the complete "<output>.partial" each writer renamed into
// place, parked until the set commits. Keyed by the output's absolute path.
struct Parked {
  std::mutex mutex;
  std::map<std::string, std::string> partial_of;  // output -> its complete partial ("" = none yet)
};
inline Parked& ParkedOutputs() {
  static Parked parked;
  return parked;
}
inline std::string Key(const std::string& path) {
  std::error_code error;
  const std::filesystem::path absolute = std::filesystem::absolute(path, error);
  return (error ? std::filesystem::path(path) : absolute).lexically_normal().string();
}

// The files whose writing failed where the writer could not throw (an HDF5 file whose close
// could not write its last data: the Id closing it is a destructor).
struct FailedWrites {
  std::mutex mutex;
  std::vector<std::string> paths;  // Key()s
};
inline FailedWrites& FailedWriteList() {
  static FailedWrites failed;
  return failed;
}

// Renames `from` onto `to` now (the last step of RenameInto).
inline void RenameNow(const std::string& from, const std::string& to) {
  namespace fs = std::filesystem;
  std::error_code error;
  const fs::file_status target = fs::status(to, error);
  if (fs::exists(target) && !fs::is_regular_file(target) && !fs::is_directory(target))
    throw std::runtime_error(to +
                             ": not a regular file (a device, FIFO or socket): not replaced "
                             "by " +
                             from);
  error.clear();
  fs::rename(from, to, error);
  if (error)
    throw std::runtime_error(to + ": cannot rename " + from + " into place: " + error.message());
}

}  // namespace files_internal

// Renames `from` onto `to` (atomic on one file system); std::runtime_error naming both if not.
// Never over anything but a regular file, a link to one, or a folder (ReplaceDirectory): a
// rename onto a character device or a FIFO would replace the device's node with a file (`--out
// /dev/null` run as root). The commands refuse such an output before any work
// (common/output_paths.h); this is the last line.
// Notes that writing `path` failed where no exception could say so (a destructor closing it):
// RenameInto will not put it in place.
inline void ReportFailedWrite(const std::string& path) {
  files_internal::FailedWrites& failed = files_internal::FailedWriteList();
  std::lock_guard<std::mutex> lock(failed.mutex);
  failed.paths.push_back(files_internal::Key(path));
}

// An output an OutputSet holds is not renamed here but parked until the set commits. A `from`
// whose writing failed (ReportFailedWrite: a full disk) is removed, and `to` left as it was.
inline void RenameInto(const std::string& from, const std::string& to) {
  {
    files_internal::FailedWrites& failed = files_internal::FailedWriteList();
    std::lock_guard<std::mutex> lock(failed.mutex);
    for (const std::string& path : failed.paths)
      if (path == files_internal::Key(from)) {
        std::remove(from.c_str());
        throw std::runtime_error(to + ": writing " + from + " failed (is the disk full?); " + to +
                                 " is left as it was");
      }
  }
  {
    files_internal::Parked& parked = files_internal::ParkedOutputs();
    std::lock_guard<std::mutex> lock(parked.mutex);
    const auto it = parked.partial_of.find(files_internal::Key(to));
    if (it != parked.partial_of.end()) {
      it->second = from;
      return;
    }
  }
  files_internal::RenameNow(from, to);
}

// The outputs of one run, put in place together once every one is complete. While a set lives,
// a writer's final rename of one of its outputs (RenameInto) is held back, the complete
// "<output>.partial" left where it is; Commit() renames them all into place, in the order given.
// A set destroyed without Commit (the run failed, on a later output or half way through one: a
// full disk) removes the partials it holds and every "<output>.partial" a writer left, so a run
// that fails leaves every existing output as it was and no partial file beside it:
//
//   OutputSet outputs({out, report});
//   WriteTracks(out, ...);       // complete in out.partial
//   WriteReport(report, ...);    // throws: out is left as it was, out.partial removed
//   outputs.Commit();
//
// Empty paths (an option not given) are skipped. One set at a time holds a given output.
class OutputSet {
 public:
  explicit OutputSet(const std::vector<std::string>& outputs) {
    files_internal::Parked& parked = files_internal::ParkedOutputs();
    std::lock_guard<std::mutex> lock(parked.mutex);
    for (const std::string& output : outputs) {
      if (output.empty()) continue;
      const std::string key = files_internal::Key(output);
      if (parked.partial_of.count(key)) continue;  // named twice: held once
      parked.partial_of[key] = "";
      outputs_.push_back(output);
      keys_.push_back(key);
    }
  }
  OutputSet(const OutputSet&) = delete;
  OutputSet& operator=(const OutputSet&) = delete;
  ~OutputSet() {
    const bool committed = keys_.empty();
    const std::vector<std::string> partials = Release();
    if (committed) return;
    for (size_t i = 0; i < outputs_.size(); ++i) {
      if (!partials[i].empty()) std::remove(partials[i].c_str());
      std::remove((outputs_[i] + ".partial").c_str());  // a writer that failed half way
    }
  }

  // Renames every output written so far into place (an output never written is skipped).
  // std::runtime_error naming the output when a rename fails: the outputs before it are in
  // place, the partials of the rest removed.
  void Commit() {
    const std::vector<std::string> partials = Release();
    for (size_t i = 0; i < partials.size(); ++i) {
      if (partials[i].empty()) continue;
      try {
        files_internal::RenameNow(partials[i], outputs_[i]);
      } catch (const std::exception&) {
        for (size_t j = i; j < partials.size(); ++j)
          if (!partials[j].empty()) std::remove(partials[j].c_str());
        throw;
      }
    }
  }

 private:
  // Stops holding the outputs back; the partial each writer left ("" for none), in order.
  std::vector<std::string> Release() {
    files_internal::Parked& parked = files_internal::ParkedOutputs();
    std::lock_guard<std::mutex> lock(parked.mutex);
    std::vector<std::string> partials;
    for (const std::string& key : keys_) {
      partials.push_back(parked.partial_of[key]);
      parked.partial_of.erase(key);
    }
    keys_.clear();
    return partials;
  }

  std::vector<std::string> outputs_, keys_;
};

// Writes `text` to `path` through "<path>.partial" and a rename: `path` is either what it was or
// the whole new text. std::runtime_error naming the file when it cannot be written (the partial
// file is removed) or renamed.
inline void WriteTextFile(const std::string& path, const std::string& text) {
  const std::string partial = path + ".partial";
  {
    std::ofstream out(partial, std::ios::trunc);
    out << text;
    out.close();
    if (!out) {
      std::remove(partial.c_str());
      throw std::runtime_error(path + ": cannot write " + partial +
                               " (is the disk full, or the folder not writable?)");
    }
  }
  RenameInto(partial, path);
}

// Whether `path` is `folder` or lies inside it, symbolic links and ".." resolved (neither needs
// to exist); false when either cannot be resolved.
inline bool IsInsideFolder(const std::string& path, const std::string& folder) {
  namespace fs = std::filesystem;
  std::error_code error;
  const fs::path f = fs::weakly_canonical(fs::absolute(folder), error);
  if (error) return false;
  const fs::path p = fs::weakly_canonical(fs::absolute(path), error);
  if (error) return false;
  const fs::path relative = p.lexically_relative(f);
  return !relative.empty() && *relative.begin() != "..";
}

// Puts the complete folder `partial` in place of the folder `dir`. A folder cannot be renamed onto
// a non-empty one, so an existing `dir` is renamed aside to "<dir>.old.<pid>" first, the partial
// renamed into place, and the old one removed; if the second rename fails the old folder is put
// back. Throws std::runtime_error naming the folders when `dir` exists but is not a folder or a
// rename fails.
inline void ReplaceDirectory(const std::string& partial, const std::string& dir) {
  namespace fs = std::filesystem;
  std::error_code error;
  const fs::file_status status = fs::symlink_status(dir, error);
  if (!fs::exists(status)) return RenameInto(partial, dir);
  if (!fs::is_directory(status))
    throw std::runtime_error(dir + ": exists and is not a folder; not replaced");
  const std::string old = dir + ".old." + std::to_string(getpid());
  fs::remove_all(old, error);
  RenameInto(dir, old);
  fs::rename(partial, dir, error);
  if (error) {
    std::error_code ignored;
    fs::rename(old, dir, ignored);
    throw std::runtime_error(dir + ": cannot rename " + partial +
                             " into place: " + error.message() + " (the previous folder is kept)");
  }
  // The new folder is in place: a failure to delete the old one loses nothing.
  fs::remove_all(old, error);
}

// A folder written whole under "<dir>.partial" and put in place of `dir` by Commit(); until then
// `dir` is untouched, and a partial folder that is never committed is removed on destruction (a
// failing run leaves no half-written folder behind). A stale partial from a killed run is removed
// first. `dir` is named without a trailing '/'; "." , ".." and "/" are refused, since the folder
// is renamed as a whole.
class FolderReplacement {
 public:
  explicit FolderReplacement(std::string dir) : dir_(Trimmed(std::move(dir))) {
    namespace fs = std::filesystem;
    const std::string name = fs::path(dir_).filename().string();
    if (dir_.empty() || name == "." || name == ".." || dir_ == "/")
      throw std::runtime_error("'" + dir_ +
                               "': name the output folder itself (it is replaced "
                               "as a whole), not '.', '..' or '/'");
    // A status error means "no such path" here (or one under a file: create_directories below
    // names that).
    std::error_code ignored, error;
    const fs::file_status status = fs::symlink_status(dir_, ignored);
    if (fs::exists(status) && !fs::is_directory(status))
      throw std::runtime_error(dir_ + ": exists and is not a folder; not replaced");
    partial_ = dir_ + ".partial";
    if (fs::exists(fs::symlink_status(partial_, ignored))) fs::remove_all(partial_, error);
    if (error)
      throw std::runtime_error(partial_ +
                               ": cannot remove the stale partial folder: " + error.message());
    fs::create_directories(partial_, error);
    if (error)
      throw std::runtime_error(partial_ + ": cannot create the output folder: " + error.message());
  }
  FolderReplacement(const FolderReplacement&) = delete;
  FolderReplacement& operator=(const FolderReplacement&) = delete;
  ~FolderReplacement() {
    if (committed_) return;
    std::error_code ignored;
    std::filesystem::remove_all(partial_, ignored);
  }

  const std::string& dir() const { return dir_; }
  // Where to write the folder's content.
  const std::string& partial() const { return partial_; }
  void Commit() {
    ReplaceDirectory(partial_, dir_);
    committed_ = true;
  }

 private:
  static std::string Trimmed(std::string dir) {
    while (dir.size() > 1 && dir.back() == '/') dir.pop_back();
    return dir;
  }

  std::string dir_, partial_;
  bool committed_ = false;
};

}  // namespace netlab
