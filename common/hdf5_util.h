#pragma once
// Thin RAII and helpers over the HDF5 C API, shared by every netlab file in HDF5 (knot tracks,
// labels, frame stores). Errors throw std::runtime_error naming the file and the object; HDF5's
// own error printing is switched off.

#include <hdf5.h>

#include <mutex>
#include <string>
#include <utility>
#include <vector>

namespace netlab::h5 {

// Owns one HDF5 identifier and closes it with the right H5*close.
class Id {
 public:
  Id() = default;
  explicit Id(hid_t id) : id_(id) {}
  Id(Id&& other) noexcept : id_(std::exchange(other.id_, H5I_INVALID_HID)) {}
  Id& operator=(Id&& other) noexcept {
    if (this != &other) {
      Reset();
      id_ = std::exchange(other.id_, H5I_INVALID_HID);
    }
    return *this;
  }
  Id(const Id&) = delete;
  Id& operator=(const Id&) = delete;
  ~Id() { Reset(); }

  hid_t get() const { return id_; }
  bool valid() const { return id_ >= 0; }
  void Reset();

 private:
  hid_t id_ = H5I_INVALID_HID;
};

// Turns off HDF5's automatic error stack printing (once per process).
void SilenceErrors();

Id CreateFile(const std::string& path);         // truncates
Id OpenFileReadOnly(const std::string& path);   // throws "cannot open ... as HDF5"
Id OpenFileReadWrite(const std::string& path);  // to add datasets to an existing file
Id CreateGroup(hid_t loc, const std::string& name);
bool Exists(hid_t loc, const std::string& path);  // a link at `path` (relative to loc)

// A chunked dataset of frames: shape [0, frame_dims...], growing along the first axis.
Id CreateFrameDataset(hid_t loc, const std::string& name, hid_t type,
                      const std::vector<hsize_t>& frame_dims, hsize_t chunk_frames,
                      int deflate_level = 0);
// Appends one frame (data of prod(frame_dims) elements of `type`) at index `frame`.
void AppendFrame(hid_t dataset, hid_t type, const void* data, hsize_t frame);

// Whole datasets.
void WriteDataset(hid_t loc, const std::string& name, hid_t type, const std::vector<hsize_t>& dims,
                  const void* data, int deflate_level = 0);
std::vector<hsize_t> DatasetDims(hid_t loc, const std::string& name);
// Reads the whole dataset converted to `type` (the buffer must hold every element).
void ReadDataset(hid_t loc, const std::string& name, hid_t type, void* data);

void WriteStringAttribute(hid_t obj, const std::string& name, const std::string& value);
// Empty string when the attribute is absent.
std::string ReadStringAttribute(hid_t obj, const std::string& name);
void WriteStringDataset(hid_t loc, const std::string& name, const std::string& value);
std::string ReadStringDataset(hid_t loc, const std::string& name);

// A list of names kept in one string attribute or dataset, a name per line (names hold no line
// break). SplitLines("") is the empty list.
std::string JoinLines(const std::vector<std::string>& lines);
std::vector<std::string> SplitLines(const std::string& text);

// Sets the "units" attribute of dataset `name` under `loc`.
void SetUnits(hid_t loc, const std::string& name, const std::string& units);

// A unit a reader accepts and the factor that turns it into the unit netlab keeps in memory
// (the first of the list).
using UnitFactors = std::vector<std::pair<std::string, double>>;
extern const UnitFactors kSeconds;       // s, ms, us, ns
extern const UnitFactors kMetres;        // m, cm, mm, um
extern const UnitFactors kSquareMetres;  // m^2, cm^2, mm^2, um^2 (covariances)
extern const UnitFactors kPixels;        // px

// The factor that turns dataset `name`'s values (in file `path`) into the unit netlab keeps in
// memory, from its "units" attribute: a unit a file states is converted or refused, never
// ignored. No attribute: the first unit, as netlab writes it. Any unit not in `known` is refused
// (std::runtime_error naming the file, the dataset and the units read).
double UnitsFactor(hid_t file, const std::string& path, const std::string& name,
                   const UnitFactors& known);

}  // namespace netlab::h5

namespace netlab::h5 {

// Reads frame `frame` (the first axis) of a dataset of rank >= 2 into `data`, converted to `type`.
void ReadFrame(hid_t dataset, hid_t type, hsize_t frame, void* data);

// The HDF5 library Debian ships is built without thread safety: every call from a thread that is
// not the only one using HDF5 must hold this lock.
std::mutex& Mutex();

}  // namespace netlab::h5
