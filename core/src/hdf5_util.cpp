#include "hdf5_util.hpp"

#include <cstdio>

#include "isochor/base/error.hpp"

namespace isochor::h5 {
namespace {

// The innermost message of HDF5's error stack: the system's reason when there is one ("No space
// left on device", "File too large"), else HDF5's description.
herr_t innermost(unsigned n, const H5E_error2_t* e, void* out) {
  if (n != 0 || !e->desc) return 0;
  std::string d = e->desc;
  const std::string key = "error message = '";
  const std::size_t at = d.find(key);
  if (at != std::string::npos) {
    const std::size_t end = d.find('\'', at + key.size());
    d = d.substr(at + key.size(), end == std::string::npos ? std::string::npos : end - at - key.size());
  }
  *static_cast<std::string*>(out) = d;
  return 0;
}
}  // namespace

std::string hdf5_reason() {
  std::string r;
  H5Ewalk2(H5E_DEFAULT, H5E_WALK_UPWARD, innermost, &r);
  H5Eclear2(H5E_DEFAULT);
  return r.empty() ? "" : " (" + r + ")";
}

void check(herr_t status, const std::string& what) {
  if (status < 0) throw Error("HDF5: " + what + " failed" + hdf5_reason());
}
hid_t checked(hid_t id, const std::string& what) {
  if (id < 0) throw Error("HDF5: " + what + " failed" + hdf5_reason());
  return id;
}

H group(hid_t loc, const std::string& name) {
  return H(checked(H5Gcreate2(loc, name.c_str(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), "create group " + name),
           H5Gclose);
}

void write_array(hid_t loc, const std::string& name, hid_t type, const std::vector<hsize_t>& dims, const void* data) {
  H space(checked(H5Screate_simple(static_cast<int>(dims.size()), dims.data(), nullptr), "dataspace"), H5Sclose);
  H ds(checked(H5Dcreate2(loc, name.c_str(), type, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), "create " + name),
       H5Dclose);
  check(H5Dwrite(ds, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data), "write " + name);
}

void string_attribute(hid_t loc, const std::string& name, const std::string& value) {
  if (H5Aexists(loc, name.c_str()) > 0) H5Adelete(loc, name.c_str());
  H type(H5Tcopy(H5T_C_S1), H5Tclose);
  H5Tset_size(type, H5T_VARIABLE);
  H5Tset_cset(type, H5T_CSET_UTF8);
  H space(H5Screate(H5S_SCALAR), H5Sclose);
  H attr(checked(H5Acreate2(loc, name.c_str(), type, space, H5P_DEFAULT, H5P_DEFAULT), "attribute " + name), H5Aclose);
  const char* p = value.c_str();
  check(H5Awrite(attr, type, &p), "write attribute " + name);
}

void number_attribute(hid_t loc, const std::string& name, double value) {
  if (H5Aexists(loc, name.c_str()) > 0) H5Adelete(loc, name.c_str());
  H space(H5Screate(H5S_SCALAR), H5Sclose);
  H attr(
      checked(H5Acreate2(loc, name.c_str(), H5T_NATIVE_DOUBLE, space, H5P_DEFAULT, H5P_DEFAULT), "attribute " + name),
      H5Aclose);
  check(H5Awrite(attr, H5T_NATIVE_DOUBLE, &value), "write attribute " + name);
}

void vector_attribute(hid_t loc, const std::string& name, const double* values, hsize_t n) {
  if (H5Aexists(loc, name.c_str()) > 0) H5Adelete(loc, name.c_str());
  H space(H5Screate_simple(1, &n, nullptr), H5Sclose);
  H attr(
      checked(H5Acreate2(loc, name.c_str(), H5T_NATIVE_DOUBLE, space, H5P_DEFAULT, H5P_DEFAULT), "attribute " + name),
      H5Aclose);
  check(H5Awrite(attr, H5T_NATIVE_DOUBLE, values), "write attribute " + name);
}

std::string frame_name(int k) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%06d", k);
  return buf;
}

std::string read_string_attribute(hid_t loc, const std::string& name) {
  if (H5Aexists(loc, name.c_str()) <= 0) return "";
  H attr(checked(H5Aopen(loc, name.c_str(), H5P_DEFAULT), "open attribute " + name), H5Aclose);
  H type(H5Aget_type(attr), H5Tclose);
  if (H5Tget_class(type) != H5T_STRING) return "";
  H mem(H5Tcopy(H5T_C_S1), H5Tclose);
  H5Tset_size(mem, H5T_VARIABLE);
  H5Tset_cset(mem, H5T_CSET_UTF8);
  char* p = nullptr;
  if (!H5Tis_variable_str(type) || H5Aread(attr, mem, &p) < 0 || !p) return "";
  std::string v = p;
  H5free_memory(p);
  return v;
}

void delete_attribute(hid_t loc, const std::string& name) {
  if (H5Aexists(loc, name.c_str()) > 0) H5Adelete(loc, name.c_str());
}

}  // namespace isochor::h5
