#pragma once
// Breaking a netlab HDF5 file for the bad-input suite (issue 21): a dataset read whole, edited
// (values or shape) and written back in place of the original, as a damaged or hand-edited file
// would hold it.

#include <functional>
#include <string>
#include <vector>

#include <hdf5.h>

#include "common/hdf5_util.h"

namespace netlab::testing {

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
