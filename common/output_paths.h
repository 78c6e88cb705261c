#pragma once
// What every command checks about its outputs before any work starts, so that a run
// never replaces one of its own inputs and a failed run leaves every existing output as it was:
//
//   - an output is not an input of the same run, nor another output of it, after ".." and
//     symbolic links are resolved (and a hard link to an input is the input), and its
//     "<output>.partial" is not an input either (it is truncated first);
//   - an output that exists is a regular file (or a link to one): a character device, a FIFO or
//     a socket is refused, never replaced through the .partial rename (netlab writes every output
//     whole to a file and renames it into place, which a device cannot take), and a folder is
//     refused where a file is written;
//   - every output's folder exists and is writable, all of them before any is written, so that a
//     run with several outputs (--out and --report) cannot write the first and fail on the second.
//
// Each path is given with the option or argument that named it ("--out", "--measured",
// "scenario"), and every message names both sides and what to do.

#include <unistd.h>

#include <filesystem>
#include <stdexcept>
#include <string>
#include <system_error>
#include <vector>

namespace netlab {

// One file a command reads or writes, and what named it on the command line.
struct NamedPath {
  std::string name;  // "--out", "--measured", "scenario" (told as "the scenario file x.yaml")
  std::string path;  // as the user gave it
};

namespace output_paths_internal {

// `path` made absolute with ".." and symbolic links resolved as far as it exists (the rest kept
// lexically); the path itself when it cannot be resolved.
inline std::filesystem::path Resolved(const std::string& path) {
  std::error_code error;
  std::filesystem::path resolved =
      std::filesystem::weakly_canonical(std::filesystem::absolute(path, error), error);
  return error ? std::filesystem::path(path).lexically_normal() : resolved;
}

// Whether `a` and `b` are one file: the same resolved path, or (both existing) the same inode.
inline bool SameFile(const std::string& a, const std::string& b) {
  if (Resolved(a) == Resolved(b)) return true;
  std::error_code error;
  return std::filesystem::equivalent(a, b, error) && !error;
}

// "--out x.h5" and, when it resolves elsewhere (a link, ".."), where to: "--out l.h5 (/d/x.h5)".
inline std::string Describe(const NamedPath& p) {
  std::string text = p.name + " " + p.path;
  const std::filesystem::path resolved = Resolved(p.path);
  if (resolved != std::filesystem::absolute(p.path).lexically_normal())
    text += " (" + resolved.string() + ")";
  return text;
}

// The option of a named output: "--to-hdf5" of "--to-hdf5 (the experiment file written beside
// it)".
inline std::string Option(const NamedPath& p) { return p.name.substr(0, p.name.find(' ')); }

// "a character device", "a FIFO", ... for an existing path that is not a regular file; "" when it
// is one (or does not exist).
inline std::string SpecialKind(const std::string& path) {
  namespace fs = std::filesystem;
  std::error_code error;
  const fs::file_status status = fs::status(path, error);  // follows links
  if (error || !fs::exists(status) || fs::is_regular_file(status)) return "";
  switch (status.type()) {
    case fs::file_type::directory: return "a folder";
    case fs::file_type::character: return "a character device";
    case fs::file_type::block: return "a block device";
    case fs::file_type::fifo: return "a FIFO (named pipe)";
    case fs::file_type::socket: return "a socket";
    default: return "not a regular file";
  }
}

}  // namespace output_paths_internal

// Throws std::runtime_error (a command's exit status 1) naming the output, its option, and what
// it collides with or why it cannot be written; see the list at the top. Inputs or outputs with
// an empty path are skipped (an option not given).
inline void CheckOutputPaths(const std::vector<NamedPath>& inputs,
                             const std::vector<NamedPath>& outputs) {
  namespace fs = std::filesystem;
  using namespace output_paths_internal;
  for (size_t i = 0; i < outputs.size(); ++i) {
    const NamedPath& out = outputs[i];
    if (out.path.empty()) continue;
    for (const NamedPath& in : inputs) {
      if (in.path.empty()) continue;
      if (SameFile(out.path, in.path))
        throw std::runtime_error(Describe(out) + " is the " + in.name + " file " + in.path +
                                 ": the output would replace the input it is made from; name "
                                 "another " +
                                 Option(out));
      if (SameFile(out.path + ".partial", in.path))
        throw std::runtime_error(Describe(out) + " would be written first to " + out.path +
                                 ".partial, which is the " + in.name + " file " + in.path +
                                 "; name another " + Option(out));
    }
    for (size_t j = 0; j < i; ++j)
      if (!outputs[j].path.empty() && SameFile(out.path, outputs[j].path))
        throw std::runtime_error(Describe(out) + " is also " + Describe(outputs[j]) +
                                 ": one run cannot write two outputs to one file; name two "
                                 "different files");
  }
  // Each output's own kind and folder, only once no output collides (a collision says more).
  for (const NamedPath& out : outputs) {
    if (out.path.empty()) continue;
    if (const std::string kind = SpecialKind(out.path); !kind.empty())
      throw std::runtime_error(
          Describe(out) + " is " + kind +
          (kind == "a folder"
               ? ": name the file to write in it"
               : ", not a regular file: netlab writes every output whole to a file and renames "
                 "it into place, which would replace " +
                     out.path + " itself; name a file"));
    fs::path folder = Resolved(out.path).parent_path();
    if (folder.empty()) folder = ".";
    std::error_code error;
    const fs::file_status status = fs::status(folder, error);
    if (!fs::exists(status))
      throw std::runtime_error(Describe(out) + ": the folder " + folder.string() +
                               " does not exist (create it first); nothing was written");
    if (!fs::is_directory(status))
      throw std::runtime_error(Describe(out) + ": " + folder.string() +
                               " is not a folder; nothing was written");
    if (access(folder.c_str(), W_OK | X_OK) != 0)
      throw std::runtime_error(Describe(out) + ": the folder " + folder.string() +
                               " is not writable; nothing was written");
  }
}

}  // namespace netlab
