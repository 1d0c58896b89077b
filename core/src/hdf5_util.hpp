// The HDF5 helpers of the run-file writer (core/src/output.cpp): handles closed by scope, checked
// calls whose errors carry HDF5's innermost reason, attributes, and per-frame series.
#pragma once
#include <hdf5.h>

#include <algorithm>
#include <string>
#include <vector>

#include "isochor/base/error.hpp"

namespace isochor::h5 {

// Closes an HDF5 handle with the right call when it goes out of scope.
class H {
 public:
  H() = default;
  H(hid_t id, herr_t (*close)(hid_t)) : id_(id), close_(close) {}
  H(H&& o) noexcept : id_(o.id_), close_(o.close_) { o.id_ = -1; }
  H& operator=(H&& o) noexcept {
    reset();
    id_ = o.id_;
    close_ = o.close_;
    o.id_ = -1;
    return *this;
  }
  ~H() { reset(); }
  void reset() {
    if (id_ >= 0 && close_) close_(id_);
    id_ = -1;
  }
  operator hid_t() const { return id_; }
  bool valid() const { return id_ >= 0; }

 private:
  hid_t id_ = -1;
  herr_t (*close_)(hid_t) = nullptr;
};

// HDF5's innermost reason for the last failure, " (reason)" or "", and the error stack cleared.
std::string hdf5_reason();
// Throw Error("HDF5: WHAT failed (reason)") for a negative status or id.
void check(herr_t status, const std::string& what);
hid_t checked(hid_t id, const std::string& what);
H group(hid_t loc, const std::string& name);
void write_array(hid_t loc, const std::string& name, hid_t type, const std::vector<hsize_t>& dims, const void* data);
// Attributes, replaced where they exist.
void string_attribute(hid_t loc, const std::string& name, const std::string& value);
void number_attribute(hid_t loc, const std::string& name, double value);
void vector_attribute(hid_t loc, const std::string& name, const double* values, hsize_t n);
// "" where the attribute is missing or not a string.
std::string read_string_attribute(hid_t loc, const std::string& name);
void delete_attribute(hid_t loc, const std::string& name);
// Frame k's name in /frames/xdmf and the sidecar: six digits.
std::string frame_name(int k);

// A dataset growing along its first dimension, one frame (row) at a time.
struct Series {
  H ds;
  std::vector<hsize_t> row;  // shape of one frame
  hid_t type = H5T_NATIVE_DOUBLE;

  Series(hid_t loc, const std::string& name, std::vector<hsize_t> row_shape, hid_t t)
      : row(std::move(row_shape)), type(t) {
    std::vector<hsize_t> dims{0}, maxdims{H5S_UNLIMITED}, chunk{1};
    for (hsize_t d : row) {
      dims.push_back(d);
      maxdims.push_back(d);
      chunk.push_back(std::max<hsize_t>(d, 1));
    }
    H space(H5Screate_simple(static_cast<int>(dims.size()), dims.data(), maxdims.data()), H5Sclose);
    H dcpl(H5Pcreate(H5P_DATASET_CREATE), H5Pclose);
    // A chunk holds about 1024 values: many frames of a small row (a reader of a long run's
    // volumes or energies reads few chunks, not one per frame: 1e5 frames of the volume took 2.9 s
    // to read at one frame per chunk, 0.01 s at 512), one frame of a row of 1024 values or more.
    hsize_t values = 1;
    for (hsize_t d : row) values *= std::max<hsize_t>(d, 1);
    chunk[0] = std::max<hsize_t>(1, 1024 / values);
    H5Pset_chunk(dcpl, static_cast<int>(chunk.size()), chunk.data());
    ds = H(checked(H5Dcreate2(loc, name.c_str(), type, space, H5P_DEFAULT, dcpl, H5P_DEFAULT), "create " + name),
           H5Dclose);
  }

  // An existing series of the file (resume).
  Series(hid_t loc, const std::string& name, hid_t t) : type(t) {
    ds = H(checked(H5Dopen2(loc, name.c_str(), H5P_DEFAULT), "open " + name), H5Dclose);
    H space(H5Dget_space(ds), H5Sclose);
    std::vector<hsize_t> dims(static_cast<std::size_t>(H5Sget_simple_extent_ndims(space)));
    H5Sget_simple_extent_dims(space, dims.data(), nullptr);
    if (dims.empty()) throw Error("HDF5: " + name + " is not a per-frame series");
    row.assign(dims.begin() + 1, dims.end());
  }

  hsize_t rows() const {
    H space(H5Dget_space(ds), H5Sclose);
    std::vector<hsize_t> dims(row.size() + 1);
    H5Sget_simple_extent_dims(space, dims.data(), nullptr);
    return dims[0];
  }

  void truncate(hsize_t frames) {
    std::vector<hsize_t> dims{frames};
    dims.insert(dims.end(), row.begin(), row.end());
    check(H5Dset_extent(ds, dims.data()), "shrink dataset");
  }

  // Frame `frame` into `out` (row-major, the row's size).
  void read(hsize_t frame, double* out) const {
    std::vector<hsize_t> start{frame}, count{1};
    for (hsize_t d : row) {
      start.push_back(0);
      count.push_back(d);
    }
    H file_space(H5Dget_space(ds), H5Sclose);
    check(H5Sselect_hyperslab(file_space, H5S_SELECT_SET, start.data(), nullptr, count.data(), nullptr), "select");
    H mem_space(H5Screate_simple(static_cast<int>(count.size()), count.data(), nullptr), H5Sclose);
    check(H5Dread(ds, H5T_NATIVE_DOUBLE, mem_space, file_space, H5P_DEFAULT, out), "read frame");
  }

  void append(hsize_t frame, const void* data) {
    std::vector<hsize_t> dims{frame + 1}, start{frame}, count{1};
    for (hsize_t d : row) {
      dims.push_back(d);
      start.push_back(0);
      count.push_back(d);
    }
    check(H5Dset_extent(ds, dims.data()), "extend dataset");
    H file_space(H5Dget_space(ds), H5Sclose);
    check(H5Sselect_hyperslab(file_space, H5S_SELECT_SET, start.data(), nullptr, count.data(), nullptr), "select");
    H mem_space(H5Screate_simple(static_cast<int>(count.size()), count.data(), nullptr), H5Sclose);
    check(H5Dwrite(ds, type, mem_space, file_space, H5P_DEFAULT, data), "write frame");
  }
};

}  // namespace isochor::h5
