#include "common/hdf5_util.h"

#include <mutex>
#include <numeric>
#include <stdexcept>
#include <string>

#include "common/files.h"

namespace netlab::h5 {
namespace {

[[noreturn]] void Fail(const std::string& message) { throw std::runtime_error(message); }

// No clean-up of the library at exit: a file whose last write failed (a full disk) cannot be
// closed, and the library's exit handler crashed on it (a segmentation fault after netlab's own
// error). Every file netlab writes is closed (Id) before the program ends.
const bool kNoExitHandler = [] {
  H5dont_atexit();
  return true;
}();

std::string ObjectName(hid_t obj) {
  char buffer[512] = {0};
  H5Iget_name(obj, buffer, sizeof(buffer));
  char file[512] = {0};
  H5Fget_name(obj, file, sizeof(file));
  return std::string(file) + ":" + buffer;
}

}  // namespace

void Id::Reset() {
  if (id_ < 0) return;
  switch (H5Iget_type(id_)) {
    case H5I_FILE: {
      // A close that fails could not write the file's last data: the file is incomplete, and
      // RenameInto refuses to put it in place of an output.
      const ssize_t length = H5Fget_name(id_, nullptr, 0);
      std::string name(length > 0 ? static_cast<size_t>(length) : 0, '\0');
      if (length > 0) H5Fget_name(id_, name.data(), name.size() + 1);
      if (H5Fclose(id_) < 0 && !name.empty()) ReportFailedWrite(name);
      break;
    }
    case H5I_GROUP: H5Gclose(id_); break;
    case H5I_DATASET: H5Dclose(id_); break;
    case H5I_DATASPACE: H5Sclose(id_); break;
    case H5I_DATATYPE: H5Tclose(id_); break;
    case H5I_ATTR: H5Aclose(id_); break;
    case H5I_GENPROP_LST: H5Pclose(id_); break;
    default: break;
  }
  id_ = H5I_INVALID_HID;
}

void SilenceErrors() {
  static std::once_flag once;
  std::call_once(once, [] { H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr); });
}

Id CreateFile(const std::string& path) {
  SilenceErrors();
  // Closing the file closes every object still open in it and writes all it holds, so that a
  // write that fails there (a full disk) fails the close, which Id reports.
  Id access(H5Pcreate(H5P_FILE_ACCESS));
  H5Pset_fclose_degree(access.get(), H5F_CLOSE_STRONG);
  Id file(H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, access.get()));
  if (!file.valid()) Fail(path + ": cannot create HDF5 file");
  return file;
}

Id OpenFileReadOnly(const std::string& path) {
  SilenceErrors();
  if (H5Fis_hdf5(path.c_str()) <= 0) Fail(path + ": missing, unreadable or not an HDF5 file");
  Id file(H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT));
  if (!file.valid()) Fail(path + ": cannot open as HDF5");
  return file;
}

Id OpenFileReadWrite(const std::string& path) {
  SilenceErrors();
  if (H5Fis_hdf5(path.c_str()) <= 0) Fail(path + ": missing, unreadable or not an HDF5 file");
  Id file(H5Fopen(path.c_str(), H5F_ACC_RDWR, H5P_DEFAULT));
  if (!file.valid()) Fail(path + ": cannot open for writing as HDF5");
  return file;
}

Id CreateGroup(hid_t loc, const std::string& name) {
  Id group(H5Gcreate2(loc, name.c_str(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT));
  if (!group.valid()) Fail(ObjectName(loc) + ": cannot create group " + name);
  return group;
}

bool Exists(hid_t loc, const std::string& path) {
  // Check each component, as H5Lexists requires the intermediate links to exist.
  size_t pos = 0;
  while (true) {
    const size_t next = path.find('/', pos + 1);
    const std::string prefix = path.substr(0, next);
    if (!prefix.empty() && prefix != "/" && H5Lexists(loc, prefix.c_str(), H5P_DEFAULT) <= 0)
      return false;
    if (next == std::string::npos) return true;
    pos = next;
  }
}

Id CreateFrameDataset(hid_t loc, const std::string& name, hid_t type,
                      const std::vector<hsize_t>& frame_dims, hsize_t chunk_frames,
                      int deflate_level) {
  std::vector<hsize_t> dims = {0};
  std::vector<hsize_t> max_dims = {H5S_UNLIMITED};
  std::vector<hsize_t> chunk = {chunk_frames};
  for (hsize_t d : frame_dims) {
    dims.push_back(d);
    max_dims.push_back(d);
    chunk.push_back(d == 0 ? 1 : d);
  }
  Id space(H5Screate_simple(static_cast<int>(dims.size()), dims.data(), max_dims.data()));
  Id props(H5Pcreate(H5P_DATASET_CREATE));
  H5Pset_chunk(props.get(), static_cast<int>(chunk.size()), chunk.data());
  if (deflate_level > 0) {
    H5Pset_shuffle(props.get());
    H5Pset_deflate(props.get(), static_cast<unsigned>(deflate_level));
  }
  Id dataset(
      H5Dcreate2(loc, name.c_str(), type, space.get(), H5P_DEFAULT, props.get(), H5P_DEFAULT));
  if (!dataset.valid()) Fail(ObjectName(loc) + ": cannot create dataset " + name);
  return dataset;
}

void AppendFrame(hid_t dataset, hid_t type, const void* data, hsize_t frame) {
  Id space(H5Dget_space(dataset));
  const int rank = H5Sget_simple_extent_ndims(space.get());
  std::vector<hsize_t> dims(rank);
  H5Sget_simple_extent_dims(space.get(), dims.data(), nullptr);
  dims[0] = frame + 1;
  if (H5Dset_extent(dataset, dims.data()) < 0) Fail(ObjectName(dataset) + ": cannot extend");
  Id file_space(H5Dget_space(dataset));
  std::vector<hsize_t> start(rank, 0), count(dims);
  start[0] = frame;
  count[0] = 1;
  H5Sselect_hyperslab(file_space.get(), H5S_SELECT_SET, start.data(), nullptr, count.data(),
                      nullptr);
  Id memory_space(H5Screate_simple(rank, count.data(), nullptr));
  if (H5Dwrite(dataset, type, memory_space.get(), file_space.get(), H5P_DEFAULT, data) < 0)
    Fail(ObjectName(dataset) + ": write failed (is the disk full?)");
}

void WriteDataset(hid_t loc, const std::string& name, hid_t type, const std::vector<hsize_t>& dims,
                  const void* data, int deflate_level) {
  Id space(H5Screate_simple(static_cast<int>(dims.size()), dims.data(), nullptr));
  Id props(H5Pcreate(H5P_DATASET_CREATE));
  const hsize_t elements =
      std::accumulate(dims.begin(), dims.end(), hsize_t{1}, std::multiplies<hsize_t>());
  if (deflate_level > 0 && elements > 0) {
    H5Pset_chunk(props.get(), static_cast<int>(dims.size()), dims.data());
    H5Pset_shuffle(props.get());
    H5Pset_deflate(props.get(), static_cast<unsigned>(deflate_level));
  }
  Id dataset(
      H5Dcreate2(loc, name.c_str(), type, space.get(), H5P_DEFAULT, props.get(), H5P_DEFAULT));
  if (!dataset.valid()) Fail(ObjectName(loc) + ": cannot create dataset " + name);
  if (elements > 0 && H5Dwrite(dataset.get(), type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data) < 0)
    Fail(ObjectName(dataset.get()) + ": write failed (is the disk full?)");
}

std::vector<hsize_t> DatasetDims(hid_t loc, const std::string& name) {
  Id dataset(H5Dopen2(loc, name.c_str(), H5P_DEFAULT));
  if (!dataset.valid()) Fail(ObjectName(loc) + ": missing dataset " + name);
  Id space(H5Dget_space(dataset.get()));
  const int rank = H5Sget_simple_extent_ndims(space.get());
  std::vector<hsize_t> dims(rank < 0 ? 0 : rank);
  H5Sget_simple_extent_dims(space.get(), dims.data(), nullptr);
  return dims;
}

void ReadDataset(hid_t loc, const std::string& name, hid_t type, void* data) {
  Id dataset(H5Dopen2(loc, name.c_str(), H5P_DEFAULT));
  if (!dataset.valid()) Fail(ObjectName(loc) + ": missing dataset " + name);
  // HDF5 converts between any two numeric types: int32 positions would be read as metres and a
  // float frame index truncated, without a word. The stored kind must be the one asked for.
  Id stored(H5Dget_type(dataset.get()));
  const H5T_class_t stored_class = H5Tget_class(stored.get()), wanted = H5Tget_class(type);
  if (stored_class != wanted && (stored_class == H5T_FLOAT || stored_class == H5T_INTEGER) &&
      (wanted == H5T_FLOAT || wanted == H5T_INTEGER)) {
    const std::string kind = stored_class == H5T_FLOAT
                                 ? std::to_string(8 * H5Tget_size(stored.get())) + "-bit float"
                                 : (H5Tget_sign(stored.get()) == H5T_SGN_NONE ? "uint" : "int") +
                                       std::to_string(8 * H5Tget_size(stored.get()));
    Fail(ObjectName(dataset.get()) + " is " + kind + ", expected " +
         (wanted == H5T_FLOAT ? "floating point" : "integers"));
  }
  Id space(H5Dget_space(dataset.get()));
  if (H5Sget_simple_extent_npoints(space.get()) == 0) return;
  if (H5Dread(dataset.get(), type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data) < 0)
    Fail(ObjectName(dataset.get()) + ": cannot read (corrupt file or wrong type)");
}

void WriteStringAttribute(hid_t obj, const std::string& name, const std::string& value) {
  Id type(H5Tcopy(H5T_C_S1));
  H5Tset_size(type.get(), value.empty() ? 1 : value.size());
  H5Tset_strpad(type.get(), H5T_STR_NULLPAD);
  Id space(H5Screate(H5S_SCALAR));
  if (H5Aexists(obj, name.c_str()) > 0) H5Adelete(obj, name.c_str());
  Id attr(H5Acreate2(obj, name.c_str(), type.get(), space.get(), H5P_DEFAULT, H5P_DEFAULT));
  if (!attr.valid()) Fail(ObjectName(obj) + ": cannot write attribute " + name);
  const std::string stored = value.empty() ? std::string(1, '\0') : value;
  H5Awrite(attr.get(), type.get(), stored.data());
}

std::string JoinLines(const std::vector<std::string>& lines) {
  std::string joined;
  for (size_t i = 0; i < lines.size(); ++i) joined += (i ? "\n" : "") + lines[i];
  return joined;
}

std::vector<std::string> SplitLines(const std::string& text) {
  std::vector<std::string> lines;
  for (size_t start = 0; !text.empty();) {
    const size_t end = text.find('\n', start);
    lines.push_back(text.substr(start, end - start));
    if (end == std::string::npos) break;
    start = end + 1;
  }
  return lines;
}

std::string ReadStringAttribute(hid_t obj, const std::string& name) {
  if (H5Aexists(obj, name.c_str()) <= 0) return "";
  Id attr(H5Aopen(obj, name.c_str(), H5P_DEFAULT));
  Id type(H5Aget_type(attr.get()));
  if (H5Tget_class(type.get()) != H5T_STRING) return "";
  if (H5Tis_variable_str(type.get()) > 0) {
    char* text = nullptr;
    Id memory_type(H5Tcopy(H5T_C_S1));
    H5Tset_size(memory_type.get(), H5T_VARIABLE);
    H5Aread(attr.get(), memory_type.get(), &text);
    std::string result = text ? text : "";
    H5free_memory(text);
    return result;
  }
  const size_t size = H5Tget_size(type.get());
  std::string value(size, '\0');
  H5Aread(attr.get(), type.get(), value.data());
  value.resize(value.find_last_not_of('\0') + 1);
  return value;
}

void WriteStringDataset(hid_t loc, const std::string& name, const std::string& value) {
  Id type(H5Tcopy(H5T_C_S1));
  H5Tset_size(type.get(), value.empty() ? 1 : value.size());
  Id space(H5Screate(H5S_SCALAR));
  Id dataset(H5Dcreate2(loc, name.c_str(), type.get(), space.get(), H5P_DEFAULT, H5P_DEFAULT,
                        H5P_DEFAULT));
  if (!dataset.valid()) Fail(ObjectName(loc) + ": cannot create dataset " + name);
  const std::string stored = value.empty() ? std::string(1, '\0') : value;
  H5Dwrite(dataset.get(), type.get(), H5S_ALL, H5S_ALL, H5P_DEFAULT, stored.data());
}

std::string ReadStringDataset(hid_t loc, const std::string& name) {
  Id dataset(H5Dopen2(loc, name.c_str(), H5P_DEFAULT));
  if (!dataset.valid()) Fail(ObjectName(loc) + ": missing dataset " + name);
  Id type(H5Dget_type(dataset.get()));
  Id space(H5Dget_space(dataset.get()));
  const std::string where = ObjectName(loc) + (ObjectName(loc).ends_with('/') ? "" : "/") + name;
  if (H5Tget_class(type.get()) != H5T_STRING)
    Fail(where + ": expected a string, the dataset holds another type");
  if (H5Sget_simple_extent_npoints(space.get()) != 1)
    Fail(where + ": expected one string (a scalar dataset), found " +
         std::to_string(H5Sget_simple_extent_npoints(space.get())) + " values");
  // A variable-length string (h5py's default) is read as a pointer to its text, not into a
  // buffer of the type's size (which is the pointer's size).
  if (H5Tis_variable_str(type.get()) > 0) {
    char* text = nullptr;
    Id memory_type(H5Tcopy(H5T_C_S1));
    H5Tset_size(memory_type.get(), H5T_VARIABLE);
    H5Tset_cset(memory_type.get(), H5Tget_cset(type.get()));
    if (H5Dread(dataset.get(), memory_type.get(), H5S_ALL, H5S_ALL, H5P_DEFAULT, &text) < 0)
      Fail(where + ": cannot read the string (corrupt file?)");
    std::string result = text ? text : "";
    H5free_memory(text);
    return result;
  }
  const size_t size = H5Tget_size(type.get());
  std::string value(size, '\0');
  if (H5Dread(dataset.get(), type.get(), H5S_ALL, H5S_ALL, H5P_DEFAULT, value.data()) < 0)
    Fail(where + ": cannot read the string (corrupt file?)");
  value.resize(value.find_last_not_of('\0') + 1);
  return value;
}

void SetUnits(hid_t loc, const std::string& name, const std::string& units) {
  Id dataset(H5Dopen2(loc, name.c_str(), H5P_DEFAULT));
  if (!dataset.valid()) Fail(ObjectName(loc) + ": missing dataset " + name);
  WriteStringAttribute(dataset.get(), "units", units);
}

void ReadFrame(hid_t dataset, hid_t type, hsize_t frame, void* data) {
  Id space(H5Dget_space(dataset));
  const int rank = H5Sget_simple_extent_ndims(space.get());
  std::vector<hsize_t> dims(rank);
  H5Sget_simple_extent_dims(space.get(), dims.data(), nullptr);
  if (rank < 1 || frame >= dims[0])
    Fail(ObjectName(dataset) + ": frame " + std::to_string(frame) + " out of range");
  std::vector<hsize_t> start(rank, 0), count(dims);
  start[0] = frame;
  count[0] = 1;
  H5Sselect_hyperslab(space.get(), H5S_SELECT_SET, start.data(), nullptr, count.data(), nullptr);
  Id memory(H5Screate_simple(rank, count.data(), nullptr));
  if (H5Dread(dataset, type, memory.get(), space.get(), H5P_DEFAULT, data) < 0)
    Fail(ObjectName(dataset) + ": cannot read frame " + std::to_string(frame) + " (corrupt file?)");
}

std::mutex& Mutex() {
  static std::mutex mutex;
  return mutex;
}

const UnitFactors kSeconds = {
    {"s", 1.0}, {"ms", 1e-3}, {"us", 1e-6}, {"\u00b5s", 1e-6}, {"ns", 1e-9}};
const UnitFactors kMetres = {
    {"m", 1.0}, {"cm", 1e-2}, {"mm", 1e-3}, {"um", 1e-6}, {"\u00b5m", 1e-6}};
const UnitFactors kSquareMetres = {{"m^2", 1.0},   {"m2", 1.0},   {"cm^2", 1e-4},
                                   {"mm^2", 1e-6}, {"mm2", 1e-6}, {"um^2", 1e-12}};
const UnitFactors kPixels = {{"px", 1.0}};

double UnitsFactor(hid_t file, const std::string& path, const std::string& name,
                   const UnitFactors& known) {
  Id dataset(H5Dopen2(file, name.c_str(), H5P_DEFAULT));
  if (!dataset.valid()) Fail(path + ": missing dataset " + name);
  std::string units = ReadStringAttribute(dataset.get(), "units");
  const size_t a = units.find_first_not_of(" \t"), b = units.find_last_not_of(" \t");
  units = a == std::string::npos ? "" : units.substr(a, b - a + 1);
  if (units.empty()) return 1.0;
  std::string names;
  for (const auto& [unit, factor] : known) {
    if (units == unit) return factor;
    names += (names.empty() ? "" : ", ") + unit;
  }
  Fail(path + ":" + name + " has units '" + units + "' (its \"units\" attribute); netlab reads " +
       names + (known.size() > 1 ? ", converted to " + known.front().first : std::string()) +
       ": convert the file or fix the attribute");
}

}  // namespace netlab::h5
