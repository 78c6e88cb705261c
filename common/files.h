#pragma once
// Replacing a file safely: everything netlab writes goes to "<path>.partial" first and is renamed
// into place when complete, so an interrupted write never destroys what the user had.

#include <filesystem>
#include <stdexcept>
#include <string>

namespace netlab {

// Renames `from` onto `to` (atomic on one file system); std::runtime_error naming both if not.
inline void RenameInto(const std::string& from, const std::string& to) {
  std::error_code error;
  std::filesystem::rename(from, to, error);
  if (error)
    throw std::runtime_error(to + ": cannot rename " + from + " into place: " + error.message());
}

}  // namespace netlab
