// The checked HDF5 access shared by the point-series writer and its readers: every HDF5 call
// is checked, and a failure becomes an exception that names the file and the object, with
// HDF5's own innermost message appended. Internal to cosim_output.
#pragma once

#include <hdf5.h>

#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include "cosim/output/point_series.hpp"

namespace cosim::output::detail {

static_assert(sizeof(int) == 4, "labels and segments are stored as int32");

// HDF5 prints its error stack to stderr by default; our exceptions carry the message instead.
void silence_hdf5();

// Throws "cosim_output: WHAT 'OBJECT' in 'FILE' failed (HDF5's innermost message)".
[[noreturn]] void fail(const std::filesystem::path& file, const std::string& object,
                       const std::string& what);

// Owns one HDF5 identifier; the close function depends on the kind of object.
class Handle {
 public:
  Handle() = default;
  Handle(hid_t id, herr_t (*close)(hid_t)) : id_(id), close_(close) {}
  Handle(Handle&& other) noexcept
      : id_(std::exchange(other.id_, H5I_INVALID_HID)), close_(other.close_) {}
  Handle& operator=(Handle&& other) noexcept {
    if (this != &other) {
      reset();
      id_ = std::exchange(other.id_, H5I_INVALID_HID);
      close_ = other.close_;
    }
    return *this;
  }
  Handle(const Handle&) = delete;
  Handle& operator=(const Handle&) = delete;
  ~Handle() { reset(); }

  hid_t get() const { return id_; }
  // Close with a checked result, for the file whose close may still write data.
  herr_t release() {
    herr_t status = 0;
    if (id_ >= 0 && close_ != nullptr) status = close_(id_);
    id_ = H5I_INVALID_HID;
    return status;
  }

 private:
  void reset() {
    if (id_ >= 0 && close_ != nullptr) close_(id_);
    id_ = H5I_INVALID_HID;
  }
  hid_t id_ = H5I_INVALID_HID;
  herr_t (*close_)(hid_t) = nullptr;
};

// Binds the file name into every check so messages always name it.
struct Checker {
  std::filesystem::path file;

  Handle id(hid_t id, herr_t (*close)(hid_t), const std::string& object,
            const std::string& what) const {
    if (id < 0) fail(file, object, what);
    return Handle(id, close);
  }
  void ok(herr_t status, const std::string& object, const std::string& what) const {
    if (status < 0) fail(file, object, what);
  }
  bool exists(hid_t loc, const std::string& name, const std::string& object) const {
    htri_t result = H5Lexists(loc, name.c_str(), H5P_DEFAULT);
    if (result < 0) fail(file, object, "checking for");
    return result > 0;
  }

  Handle create_group(hid_t loc, const std::string& name, const std::string& object) const {
    return id(H5Gcreate2(loc, name.c_str(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), H5Gclose,
              object, "creating group");
  }
  Handle open_group(hid_t loc, const std::string& name, const std::string& object) const {
    return id(H5Gopen2(loc, name.c_str(), H5P_DEFAULT), H5Gclose, object, "opening group");
  }

  // Writes a dataset with its `unit`, `description` and (when given) `legend` attributes.
  void write(hid_t loc, const std::string& name, const std::string& object, hid_t file_type,
             hid_t mem_type, const std::vector<hsize_t>& dims, const void* data,
             const FieldInfo& info) const {
    Handle space = id(H5Screate_simple(static_cast<int>(dims.size()), dims.data(), nullptr),
                      H5Sclose, object, "creating dataspace for");
    Handle dset = id(H5Dcreate2(loc, name.c_str(), file_type, space.get(), H5P_DEFAULT, H5P_DEFAULT,
                                H5P_DEFAULT),
                     H5Dclose, object, "creating dataset");
    hsize_t total = 1;
    for (hsize_t d : dims) total *= d;
    // An empty vector may hand out a null pointer, which H5Dwrite rejects.
    if (total > 0) {
      ok(H5Dwrite(dset.get(), mem_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data), object,
         "writing dataset");
    }
    annotate(dset.get(), object, info);
  }

  void annotate(hid_t dataset, const std::string& object, const FieldInfo& info) const {
    write_string(dataset, "unit", info.unit, object);
    write_string(dataset, "description", info.description, object);
    if (!info.legend.empty()) write_string(dataset, "legend", info.legend, object);
  }

  // A variable-length UTF-8 string attribute (what h5py and HDFView show as text).
  void write_string(hid_t loc, const std::string& name, const std::string& value,
                    const std::string& object) const {
    const std::string target = object + "@" + name;
    Handle type = id(H5Tcopy(H5T_C_S1), H5Tclose, target, "creating string type for");
    ok(H5Tset_size(type.get(), H5T_VARIABLE), target, "sizing string type for");
    ok(H5Tset_cset(type.get(), H5T_CSET_UTF8), target, "setting character set of");
    Handle space = id(H5Screate(H5S_SCALAR), H5Sclose, target, "creating dataspace for");
    if (H5Aexists(loc, name.c_str()) > 0) {
      ok(H5Adelete(loc, name.c_str()), target, "replacing attribute");
    }
    Handle attr =
        id(H5Acreate2(loc, name.c_str(), type.get(), space.get(), H5P_DEFAULT, H5P_DEFAULT),
           H5Aclose, target, "creating attribute");
    const char* text = value.c_str();
    ok(H5Awrite(attr.get(), type.get(), &text), target, "writing attribute");
  }

  // A string attribute (variable or fixed length), or "" when there is none.
  std::string read_string(hid_t loc, const std::string& name, const std::string& object) const {
    const std::string target = object + "@" + name;
    const htri_t present = H5Aexists(loc, name.c_str());
    if (present < 0) fail(file, target, "checking for");
    if (present == 0) return "";
    Handle attr =
        id(H5Aopen(loc, name.c_str(), H5P_DEFAULT), H5Aclose, target, "opening attribute");
    Handle stored = id(H5Aget_type(attr.get()), H5Tclose, target, "getting type of");
    if (H5Tget_class(stored.get()) != H5T_STRING) return "";
    Handle type = id(H5Tcopy(H5T_C_S1), H5Tclose, target, "creating string type for");
    // HDF5 converts no character set into another: read in the stored one.
    ok(H5Tset_cset(type.get(), H5Tget_cset(stored.get())), target, "setting character set of");
    if (H5Tis_variable_str(stored.get()) > 0) {
      ok(H5Tset_size(type.get(), H5T_VARIABLE), target, "sizing string type for");
      char* text = nullptr;
      ok(H5Aread(attr.get(), type.get(), &text), target, "reading attribute");
      std::string value = text != nullptr ? text : "";
      H5free_memory(text);
      return value;
    }
    const std::size_t size = H5Tget_size(stored.get());
    ok(H5Tset_size(type.get(), size + 1), target, "sizing string type for");
    std::string value(size + 1, '\0');
    ok(H5Aread(attr.get(), type.get(), value.data()), target, "reading attribute");
    value.resize(value.find('\0'));
    return value;
  }

  // Appends one value to a 1D chunked dataset that grows without bound, creating it first.
  void append(hid_t loc, const std::string& name, const std::string& object, double value,
              const FieldInfo& info) const {
    if (!exists(loc, name, object)) {
      const hsize_t dims[1] = {0};
      const hsize_t max_dims[1] = {H5S_UNLIMITED};
      const hsize_t chunk[1] = {256};
      Handle space =
          id(H5Screate_simple(1, dims, max_dims), H5Sclose, object, "creating dataspace for");
      Handle plist = id(H5Pcreate(H5P_DATASET_CREATE), H5Pclose, object, "creating plist for");
      ok(H5Pset_chunk(plist.get(), 1, chunk), object, "chunking");
      Handle created = id(H5Dcreate2(loc, name.c_str(), H5T_IEEE_F64LE, space.get(), H5P_DEFAULT,
                                     plist.get(), H5P_DEFAULT),
                          H5Dclose, object, "creating dataset");
      annotate(created.get(), object, info);
    }
    Handle dset = id(H5Dopen2(loc, name.c_str(), H5P_DEFAULT), H5Dclose, object, "opening dataset");
    hsize_t size = 0;
    {
      Handle space = id(H5Dget_space(dset.get()), H5Sclose, object, "getting dataspace of");
      if (H5Sget_simple_extent_dims(space.get(), &size, nullptr) != 1) {
        fail(file, object, "getting size of");
      }
    }
    const hsize_t grown = size + 1;
    ok(H5Dset_extent(dset.get(), &grown), object, "extending dataset");
    Handle space = id(H5Dget_space(dset.get()), H5Sclose, object, "getting dataspace of");
    const hsize_t count = 1;
    ok(H5Sselect_hyperslab(space.get(), H5S_SELECT_SET, &size, nullptr, &count, nullptr), object,
       "selecting the end of");
    Handle memory =
        id(H5Screate_simple(1, &count, nullptr), H5Sclose, object, "creating dataspace for");
    ok(H5Dwrite(dset.get(), H5T_NATIVE_DOUBLE, memory.get(), space.get(), H5P_DEFAULT, &value),
       object, "appending to dataset");
  }

  // Reads a dataset of `rank` dimensions whose second dimension (if any) must equal `cols`.
  template <typename T>
  std::vector<T> read(hid_t loc, const std::string& name, const std::string& object, hid_t mem_type,
                      int rank, hsize_t cols, std::size_t& rows) const {
    Handle dset = id(H5Dopen2(loc, name.c_str(), H5P_DEFAULT), H5Dclose, object, "opening dataset");
    Handle space = id(H5Dget_space(dset.get()), H5Sclose, object, "getting dataspace of");
    int actual_rank = H5Sget_simple_extent_ndims(space.get());
    if (actual_rank < 0) fail(file, object, "getting rank of");
    hsize_t dims[2] = {0, 0};
    if (actual_rank != rank || H5Sget_simple_extent_dims(space.get(), dims, nullptr) < 0 ||
        (rank == 2 && dims[1] != cols)) {
      throw std::runtime_error("cosim_output: dataset '" + object + "' in '" + file.string() +
                               "' has an unexpected shape");
    }
    rows = static_cast<std::size_t>(dims[0]);
    std::vector<T> data(rows * (rank == 2 ? cols : 1));
    if (!data.empty()) {
      ok(H5Dread(dset.get(), mem_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data.data()), object,
         "reading dataset");
    }
    return data;
  }

  std::vector<std::string> children(hid_t group, const std::string& object) const {
    H5G_info_t info;
    ok(H5Gget_info(group, &info), object, "listing group");
    std::vector<std::string> names;
    for (hsize_t i = 0; i < info.nlinks; ++i) {
      ssize_t size =
          H5Lget_name_by_idx(group, ".", H5_INDEX_NAME, H5_ITER_INC, i, nullptr, 0, H5P_DEFAULT);
      if (size < 0) fail(file, object, "listing group");
      std::string name(static_cast<std::size_t>(size) + 1, '\0');
      if (H5Lget_name_by_idx(group, ".", H5_INDEX_NAME, H5_ITER_INC, i, name.data(), name.size(),
                             H5P_DEFAULT) < 0) {
        fail(file, object, "listing group");
      }
      name.resize(static_cast<std::size_t>(size));
      names.push_back(std::move(name));
    }
    return names;
  }
};

std::string frame_group(int index);

std::vector<double> flatten(const std::vector<Eigen::Vector3d>& points);
std::vector<Eigen::Vector3d> unflatten(const std::vector<double>& flat);

// Locking is off for writer and readers alike: HDF5 refuses to open one file twice in a process
// with different locking flags, and a held lock would stop ParaView watching a running job.
Handle access_list(const Checker& c);
Handle open_for_reading(const std::filesystem::path& h5_path);
int frames_in(const Checker& c, hid_t file);

}  // namespace cosim::output::detail
