#pragma once
// Breaking a valid HDF5 file the way a user's tool or a bad copy would (the bad-input suites):
// one value changed, a dataset stored as another type, its values or shape edited. netlab's
// writers refuse to write such files, so the tests write a good one and edit it here.

#include <hdf5.h>

#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/hdf5_util.h"

namespace netlab::testing {

// Sets element `index` (flat, row-major) of a numeric dataset to `value`, in its stored type.
inline void PokeH5(const std::string& path, const std::string& name, size_t index, double value) {
  const hid_t file = H5Fopen(path.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
  const hid_t dataset = H5Dopen2(file, name.c_str(), H5P_DEFAULT);
  if (file < 0 || dataset < 0) throw std::runtime_error(path + ": cannot open " + name);
  const hid_t space = H5Dget_space(dataset);
  std::vector<double> values(H5Sget_simple_extent_npoints(space));
  H5Dread(dataset, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, values.data());
  values.at(index) = value;
  H5Dwrite(dataset, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, values.data());
  H5Sclose(space);
  H5Dclose(dataset);
  H5Fclose(file);
}

// Sets every element of a numeric dataset to `value`.
inline void FillH5(const std::string& path, const std::string& name, double value) {
  const hid_t file = H5Fopen(path.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
  const hid_t dataset = H5Dopen2(file, name.c_str(), H5P_DEFAULT);
  if (file < 0 || dataset < 0) throw std::runtime_error(path + ": cannot open " + name);
  const hid_t space = H5Dget_space(dataset);
  std::vector<double> values(H5Sget_simple_extent_npoints(space), value);
  H5Dwrite(dataset, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, values.data());
  H5Sclose(space);
  H5Dclose(dataset);
  H5Fclose(file);
}

// Stores dataset `name` again as int32 (values truncated), same shape and attributes dropped.
inline void RetypeH5ToInt32(const std::string& path, const std::string& name) {
  const hid_t file = H5Fopen(path.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
  hid_t dataset = H5Dopen2(file, name.c_str(), H5P_DEFAULT);
  if (file < 0 || dataset < 0) throw std::runtime_error(path + ": cannot open " + name);
  const hid_t space = H5Dget_space(dataset);
  std::vector<double> values(H5Sget_simple_extent_npoints(space));
  H5Dread(dataset, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, values.data());
  H5Dclose(dataset);
  H5Ldelete(file, name.c_str(), H5P_DEFAULT);
  std::vector<int> ints(values.begin(), values.end());
  dataset =
      H5Dcreate2(file, name.c_str(), H5T_STD_I32LE, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
  H5Dwrite(dataset, H5T_NATIVE_INT, H5S_ALL, H5S_ALL, H5P_DEFAULT, ints.data());
  H5Sclose(space);
  H5Dclose(dataset);
  H5Fclose(file);
}

// Rewrites `file`:`name` of element type T (`type` in memory) after `edit` changed its values
// or its dims (the values then must number the dims' product).
template <typename T>
void EditDataset(const std::string& file, const std::string& name, hid_t type,
                 const std::function<void(std::vector<T>&, std::vector<hsize_t>&)>& edit) {
  h5::Id f = h5::OpenFileReadWrite(file);
  std::vector<hsize_t> dims = h5::DatasetDims(f.get(), name);
  size_t count = 1;
  for (hsize_t d : dims) count *= d;
  std::vector<T> values(count);
  h5::ReadDataset(f.get(), name, type, values.data());
  edit(values, dims);
  H5Ldelete(f.get(), name.c_str(), H5P_DEFAULT);
  h5::WriteDataset(f.get(), name, type, dims, values.data());
}

}  // namespace netlab::testing
