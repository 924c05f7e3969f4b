// HDF5 side of the point series. Every HDF5 call is checked; failures become exceptions that
// name the file and the object, with HDF5's own innermost message appended.
#include "cosim/output/point_series.hpp"

#include <hdf5.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <set>
#include <stdexcept>
#include <utility>

#include "xdmf.hpp"

namespace cosim::output {
namespace {

static_assert(sizeof(int) == 4, "labels and segments are stored as int32");

// HDF5 prints its error stack to stderr by default; our exceptions carry the message instead.
void silence_hdf5() {
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
}

herr_t take_innermost(unsigned n, const H5E_error2_t* err, void* data) {
  if (n == 0 && err != nullptr && err->desc != nullptr) {
    *static_cast<std::string*>(data) = err->desc;
  }
  return 0;
}

// HDF5's file driver reports a failed system call as "file write failed: time = ..., filename
// = ..., errno = 28, error message = 'No space left on device', buf = 0x..., ...": keep what
// names the cause, drop the clock, the pointers and the byte counts.
std::string shorten_driver_message(const std::string& message) {
  const std::string marker = "error message = '";
  const auto start = message.find(marker);
  if (start == std::string::npos) return message;
  const auto end = message.find('\'', start + marker.size());
  if (end == std::string::npos) return message;
  const std::string cause = message.substr(start + marker.size(), end - start - marker.size());
  return message.substr(0, message.find(':')) + ": " + cause;
}

std::string hdf5_message() {
  std::string message;
  H5Ewalk2(H5E_DEFAULT, H5E_WALK_UPWARD, take_innermost, &message);
  H5Eclear2(H5E_DEFAULT);
  return message.empty() ? std::string() : " (" + shorten_driver_message(message) + ")";
}

[[noreturn]] void fail(const std::filesystem::path& file, const std::string& object,
                       const std::string& what) {
  // "/" stands for the file itself, which needs no separate object name.
  const std::string target =
      object == "/" ? "'" + file.string() + "'" : "'" + object + "' in '" + file.string() + "'";
  throw std::runtime_error("cosim_output: " + what + " " + target + " failed" + hdf5_message());
}

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

std::string frame_group(int index) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "/frames/%06d", index);
  return buffer;
}

// Names become HDF5 link names, so they must be single path components.
void check_name(const std::string& name, const std::string& kind) {
  if (name.empty() || name == "." || name == ".." || name.find('/') != std::string::npos) {
    throw std::invalid_argument("cosim_output: invalid " + kind + " name '" + name + "'");
  }
}

void validate(const PointFrame& frame) {
  const std::size_t n = frame.positions.size();
  auto size_check = [n](const std::string& kind, const std::string& name, std::size_t size) {
    check_name(name, kind);
    if (size != n) {
      throw std::invalid_argument("cosim_output: " + kind + " '" + name + "' has " +
                                  std::to_string(size) + " entries for " + std::to_string(n) +
                                  " points");
    }
  };
  for (const auto& [name, values] : frame.scalars) size_check("scalar", name, values.size());
  for (const auto& [name, values] : frame.vectors) size_check("vector", name, values.size());
  for (const auto& [name, values] : frame.labels) size_check("label", name, values.size());
  for (const auto& segment : frame.segments) {
    for (int end : segment) {
      if (end < 0 || static_cast<std::size_t>(end) >= n) {
        throw std::invalid_argument("cosim_output: segment end " + std::to_string(end) +
                                    " outside 0.." + std::to_string(n));
      }
    }
  }
}

std::vector<double> flatten(const std::vector<Eigen::Vector3d>& points) {
  std::vector<double> flat;
  flat.reserve(points.size() * 3);
  for (const auto& p : points) flat.insert(flat.end(), {p.x(), p.y(), p.z()});
  return flat;
}

std::vector<Eigen::Vector3d> unflatten(const std::vector<double>& flat) {
  std::vector<Eigen::Vector3d> points(flat.size() / 3);
  for (std::size_t i = 0; i < points.size(); ++i) {
    points[i] = Eigen::Vector3d(flat[3 * i], flat[3 * i + 1], flat[3 * i + 2]);
  }
  return points;
}

// Locking is off for writer and readers alike: HDF5 refuses to open one file twice in a process
// with different locking flags, and a held lock would stop ParaView watching a running job.
Handle access_list(const Checker& c) {
  Handle fapl = c.id(H5Pcreate(H5P_FILE_ACCESS), H5Pclose, "/", "creating access list for");
#if H5_VERSION_GE(1, 10, 7)
  c.ok(H5Pset_file_locking(fapl.get(), false, true), "/", "disabling file locking for");
#endif
  return fapl;
}

Handle open_for_reading(const std::filesystem::path& h5_path) {
  silence_hdf5();
  std::error_code ec;
  if (!std::filesystem::is_regular_file(h5_path, ec)) {
    throw std::runtime_error("cosim_output: no such file '" + h5_path.string() + "'");
  }
  const Checker c{h5_path};
  Handle fapl = access_list(c);
  return c.id(H5Fopen(h5_path.string().c_str(), H5F_ACC_RDONLY, fapl.get()), H5Fclose, "/",
              "opening HDF5 file");
}

int frames_in(const Checker& c, hid_t file) {
  Handle frames = c.open_group(file, "/frames", "/frames");
  H5G_info_t info;
  c.ok(H5Gget_info(frames.get(), &info), "/frames", "listing group");
  return static_cast<int>(info.nlinks);
}

// What the writer's own datasets mean; fields fall back to a description naming them.
FieldInfo completed(FieldInfo info, const std::string& default_unit,
                    const std::string& default_description) {
  if (info.unit.empty()) info.unit = default_unit;
  if (info.description.empty()) info.description = default_description;
  return info;
}

constexpr const char* kUnspecified = "unspecified";
constexpr const char* kFramePrefix = "frame_";

}  // namespace

struct PointSeriesWriter::Impl {
  std::filesystem::path h5;
  std::filesystem::path xmf;
  std::string title;
  Handle file;
  std::vector<detail::FrameIndex> frames;
  std::map<std::string, FieldInfo> fields;            // from describe()
  std::set<std::size_t> polyvertex_sizes;             // /topology/polyvertex_<n> written
  std::map<std::string, detail::SeriesIndex> series;  // written by callers, for the XDMF

  Checker checker() const { return Checker{h5}; }
  void write_xdmf() const {
    std::vector<detail::SeriesIndex> sampled;
    sampled.reserve(series.size());
    for (const auto& [name, s] : series) sampled.push_back(s);
    detail::write_file_atomically(
        xmf, detail::render_xdmf(title, h5.filename().string(), frames, sampled));
  }
  void flush() const { checker().ok(H5Fflush(file.get(), H5F_SCOPE_GLOBAL), "/", "flushing"); }

  FieldInfo field_info(const std::string& name, const std::string& kind,
                       const std::string& default_unit) const {
    const auto found = fields.find(name);
    return completed(found != fields.end() ? found->second : FieldInfo{}, default_unit,
                     kind + " '" + name + "'");
  }

  // The vertex cells 0..n-1 that the XDMF Polyvertex topology of an n-point frame refers to:
  // the Xdmf3 readers make no cells from a Polyvertex topology without explicit connectivity.
  std::string polyvertex(std::size_t n) {
    const std::string name = "polyvertex_" + std::to_string(n);
    const std::string object = "/topology/" + name;
    if (polyvertex_sizes.insert(n).second) {
      const Checker c = checker();
      Handle topology = c.open_group(file.get(), "/topology", "/topology");
      std::vector<int> cells(n);
      for (std::size_t i = 0; i < n; ++i) cells[i] = static_cast<int>(i);
      c.write(topology.get(), name, object, H5T_STD_I32LE, H5T_NATIVE_INT,
              {static_cast<hsize_t>(n)}, cells.data(),
              {"1",
               "vertex cells 0.." + std::to_string(n) + "-1 of every frame with " +
                   std::to_string(n) + " points (XDMF Polyvertex connectivity)",
               ""});
    }
    return object;
  }

  // One sample of an automatic frame series: appended on disk, kept for the XDMF.
  void append_frame_series(detail::FrameIndex& index, const std::string& name, double value,
                           const FieldInfo& info) {
    const Checker c = checker();
    const std::string g = "/series/" + name;
    Handle all = c.open_group(file.get(), "/series", "/series");
    Handle group = c.exists(all.get(), name, g) ? c.open_group(all.get(), name, g)
                                                : c.create_group(all.get(), name, g);
    c.append(group.get(), "time", g + "/time", index.time,
             {"s", "simulated time of the frame", ""});
    c.append(group.get(), "values", g + "/values", value, info);
    index.grid_values.emplace_back(name, value);
  }

  void append_frame_statistics(detail::FrameIndex& index, const PointFrame& frame) {
    append_frame_series(index, "frame_points", static_cast<double>(frame.positions.size()),
                        {"1", "number of points in the frame", ""});
    if (frame.positions.empty()) return;
    for (const auto& [name, values] : frame.scalars) {
      const FieldInfo field = field_info(name, "scalar field", kUnspecified);
      double sum = 0.0;
      for (double v : values) sum += v;
      const auto [low, high] = std::minmax_element(values.begin(), values.end());
      const std::string prefix = kFramePrefix + name;
      append_frame_series(
          index, prefix + "_min", *low,
          {field.unit, "smallest over the frame's points of: " + field.description, ""});
      append_frame_series(
          index, prefix + "_max", *high,
          {field.unit, "largest over the frame's points of: " + field.description, ""});
      append_frame_series(
          index, prefix + "_mean", sum / static_cast<double>(values.size()),
          {field.unit, "mean over the frame's points of: " + field.description, ""});
    }
    for (const auto& [name, values] : frame.vectors) {
      const FieldInfo field = field_info(name, "vector field", kUnspecified);
      double largest = 0.0;
      for (const auto& v : values) largest = std::max(largest, v.norm());
      append_frame_series(
          index, kFramePrefix + name + "_max_magnitude", largest,
          {field.unit, "largest magnitude over the frame's points of: " + field.description, ""});
    }
  }
};

PointSeriesWriter::PointSeriesWriter(const std::filesystem::path& stem, std::string title)
    : impl_(std::make_unique<Impl>()) {
  silence_hdf5();
  impl_->h5 = stem;
  impl_->h5 += ".h5";  // appended, not replaced, so stems like "run.v2" keep their dot
  impl_->xmf = stem;
  impl_->xmf += ".xmf";
  impl_->title = std::move(title);
  if (stem.has_parent_path()) std::filesystem::create_directories(stem.parent_path());

  const Checker c = impl_->checker();
  Handle fapl = access_list(c);
  impl_->file = c.id(H5Fcreate(impl_->h5.string().c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, fapl.get()),
                     H5Fclose, "/", "creating HDF5 file");
  c.write_string(impl_->file.get(), "title", impl_->title, "/");
  c.create_group(impl_->file.get(), "/frames", "/frames");
  c.create_group(impl_->file.get(), "/topology", "/topology");
  c.create_group(impl_->file.get(), "/series", "/series");
  impl_->flush();
  // Replaces any index left by an earlier run that would now point at missing frames.
  impl_->write_xdmf();
}

PointSeriesWriter::~PointSeriesWriter() = default;

void PointSeriesWriter::describe(const std::string& name, FieldInfo info) {
  check_name(name, "field");
  impl_->fields[name] = std::move(info);
}

void PointSeriesWriter::write_frame(const PointFrame& frame) {
  validate(frame);
  const Checker c = impl_->checker();
  const hid_t file = impl_->file.get();
  detail::FrameIndex index;
  index.group = frame_group(frame_count());
  index.time = frame.time;
  index.points = frame.positions.size();
  index.segments = frame.segments.size();
  const std::string& g = index.group;
  const hsize_t n = index.points;
  if (n > 0) index.topology = impl_->polyvertex(index.points);

  try {
    Handle group = c.create_group(file, g, g);
    {
      Handle space = c.id(H5Screate(H5S_SCALAR), H5Sclose, g + "@time", "creating dataspace for");
      Handle attr = c.id(
          H5Acreate2(group.get(), "time", H5T_IEEE_F64LE, space.get(), H5P_DEFAULT, H5P_DEFAULT),
          H5Aclose, g + "@time", "creating attribute");
      c.ok(H5Awrite(attr.get(), H5T_NATIVE_DOUBLE, &frame.time), g + "@time", "writing attribute");
      c.write_string(group.get(), "time_unit", "s", g);
    }
    c.write(group.get(), "positions", g + "/positions", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, {n, 3},
            flatten(frame.positions).data(), {"m", "point positions (x, y, z)", ""});

    Handle scalars = c.create_group(group.get(), "scalars", g + "/scalars");
    for (const auto& [name, values] : frame.scalars) {
      c.write(scalars.get(), name, g + "/scalars/" + name, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, {n},
              values.data(), impl_->field_info(name, "scalar field", kUnspecified));
      index.scalars.push_back(name);
    }
    Handle vectors = c.create_group(group.get(), "vectors", g + "/vectors");
    for (const auto& [name, values] : frame.vectors) {
      c.write(vectors.get(), name, g + "/vectors/" + name, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE,
              {n, 3}, flatten(values).data(),
              impl_->field_info(name, "vector field", kUnspecified));
      index.vectors.push_back(name);
    }
    Handle labels = c.create_group(group.get(), "labels", g + "/labels");
    for (const auto& [name, values] : frame.labels) {
      c.write(labels.get(), name, g + "/labels/" + name, H5T_STD_I32LE, H5T_NATIVE_INT, {n},
              values.data(), impl_->field_info(name, "integer label", "1"));
      index.labels.push_back(name);
    }
    if (!frame.segments.empty()) {
      // std::array<int, 2> is two contiguous ints, so the vector is already an M x 2 block.
      static_assert(sizeof(std::array<int, 2>) == 2 * sizeof(int));
      c.write(group.get(), "segments", g + "/segments", H5T_STD_I32LE, H5T_NATIVE_INT,
              {static_cast<hsize_t>(frame.segments.size()), 2}, frame.segments.data(),
              {"1", "line segments: pairs of indices into positions", ""});
    }
  } catch (...) {
    // Drop the partial group so the frame numbering and readers stay consistent.
    H5Ldelete(file, g.c_str(), H5P_DEFAULT);
    H5Eclear2(H5E_DEFAULT);
    throw;
  }
  // The frame is complete; its statistics follow it into /series.
  impl_->append_frame_statistics(index, frame);
  impl_->flush();
  impl_->frames.push_back(std::move(index));
  // Index after the data is on disk, so the .xmf never references a missing frame.
  impl_->write_xdmf();
}

void PointSeriesWriter::write_series(const std::string& name, const std::vector<double>& times,
                                     const std::vector<double>& values, const SeriesInfo& info) {
  check_name(name, "series");
  if (name.starts_with(kFramePrefix)) {
    throw std::invalid_argument("cosim_output: series name '" + name + "' is reserved: names " +
                                "starting with '" + kFramePrefix + "' are the frame statistics");
  }
  if (times.size() != values.size()) {
    throw std::invalid_argument("cosim_output: series '" + name + "' has " +
                                std::to_string(times.size()) + " times but " +
                                std::to_string(values.size()) + " values");
  }
  if (info.reference_times.size() != info.reference_values.size()) {
    throw std::invalid_argument("cosim_output: the reference of series '" + name + "' has " +
                                std::to_string(info.reference_times.size()) + " times but " +
                                std::to_string(info.reference_values.size()) + " values");
  }
  const Checker c = impl_->checker();
  const std::string g = "/series/" + name;
  Handle series = c.open_group(impl_->file.get(), "/series", "/series");
  // HDF5 datasets have fixed size here, so a rewrite replaces the whole group.
  if (c.exists(series.get(), name, g)) {
    c.ok(H5Ldelete(series.get(), name.c_str(), H5P_DEFAULT), g, "deleting");
  }
  Handle group = c.create_group(series.get(), name, g);
  const std::string unit = info.unit.empty() ? kUnspecified : info.unit;
  const std::string description =
      info.description.empty() ? "time series '" + name + "'" : info.description;
  const std::vector<hsize_t> dims{static_cast<hsize_t>(times.size())};
  c.write(group.get(), "time", g + "/time", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, dims, times.data(),
          {"s", "simulated time", ""});
  c.write(group.get(), "values", g + "/values", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, dims,
          values.data(), {unit, description, ""});
  if (!info.reference_times.empty()) {
    const std::vector<hsize_t> reference_dims{static_cast<hsize_t>(info.reference_times.size())};
    const std::string source =
        info.reference_source.empty() ? "reference" : "reference: " + info.reference_source;
    c.write(group.get(), "reference_time", g + "/reference_time", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE,
            reference_dims, info.reference_times.data(),
            {"s", "simulated time of the reference", ""});
    c.write(group.get(), "reference_values", g + "/reference_values", H5T_IEEE_F64LE,
            H5T_NATIVE_DOUBLE, reference_dims, info.reference_values.data(),
            {unit, source + " for " + description, ""});
  }
  if (!info.reference_source.empty()) {
    c.write_string(group.get(), "reference_source", info.reference_source, g);
  }
  impl_->flush();
  impl_->series[name] = detail::SeriesIndex{name, times, values};
  // Frames already written now carry this series in the index too.
  impl_->write_xdmf();
}

int PointSeriesWriter::frame_count() const {
  return static_cast<int>(impl_->frames.size());
}
std::filesystem::path PointSeriesWriter::h5_path() const {
  return impl_->h5;
}
std::filesystem::path PointSeriesWriter::xdmf_path() const {
  return impl_->xmf;
}

int count_point_frames(const std::filesystem::path& h5_path) {
  Handle file = open_for_reading(h5_path);
  return frames_in(Checker{h5_path}, file.get());
}

namespace {
double frame_time_of(const Checker& c, hid_t group, const std::string& g) {
  double time = 0.0;
  Handle attr =
      c.id(H5Aopen(group, "time", H5P_DEFAULT), H5Aclose, g + "@time", "opening attribute");
  c.ok(H5Aread(attr.get(), H5T_NATIVE_DOUBLE, &time), g + "@time", "reading attribute");
  return time;
}
}  // namespace

double read_point_frame_time(const std::filesystem::path& h5_path, int index) {
  Handle file = open_for_reading(h5_path);
  const Checker c{h5_path};
  const int count = frames_in(c, file.get());
  if (index < 0 || index >= count) {
    throw std::out_of_range("cosim_output: frame index " + std::to_string(index) +
                            " out of range for '" + h5_path.string() + "' with " +
                            std::to_string(count) + " frames");
  }
  const std::string g = frame_group(index);
  Handle group = c.open_group(file.get(), g, g);
  return frame_time_of(c, group.get(), g);
}

int nearest_point_frame(const std::filesystem::path& h5_path, double time) {
  const int frames = count_point_frames(h5_path);
  if (frames == 0) return -1;
  int low = 0, high = frames - 1;  // the first frame at or after the time, or the last
  while (low < high) {
    const int middle = (low + high) / 2;
    if (read_point_frame_time(h5_path, middle) < time) {
      low = middle + 1;
    } else {
      high = middle;
    }
  }
  if (low > 0 && std::abs(read_point_frame_time(h5_path, low - 1) - time) <
                     std::abs(read_point_frame_time(h5_path, low) - time)) {
    return low - 1;
  }
  return low;
}

PointFrame read_point_frame(const std::filesystem::path& h5_path, int index) {
  Handle file = open_for_reading(h5_path);
  const Checker c{h5_path};
  const int count = frames_in(c, file.get());
  const int resolved = index < 0 ? count + index : index;
  if (resolved < 0 || resolved >= count) {
    throw std::out_of_range("cosim_output: frame index " + std::to_string(index) +
                            " out of range for '" + h5_path.string() + "' with " +
                            std::to_string(count) + " frames");
  }
  const std::string g = frame_group(resolved);
  Handle group = c.open_group(file.get(), g, g);

  PointFrame frame;
  frame.time = frame_time_of(c, group.get(), g);
  std::size_t n = 0;
  frame.positions = unflatten(
      c.read<double>(group.get(), "positions", g + "/positions", H5T_NATIVE_DOUBLE, 2, 3, n));

  auto check_rows = [&](const std::string& object, std::size_t rows) {
    if (rows != n) {
      throw std::runtime_error("cosim_output: dataset '" + object + "' in '" + h5_path.string() +
                               "' has " + std::to_string(rows) + " rows for " + std::to_string(n) +
                               " points");
    }
  };
  // Each field kind lives in its own subgroup; a missing subgroup just means none of that kind.
  auto for_each_field = [&](const std::string& sub, auto&& read_one) {
    if (!c.exists(group.get(), sub, g + "/" + sub)) return;
    Handle fields = c.open_group(group.get(), sub, g + "/" + sub);
    for (const auto& name : c.children(fields.get(), g + "/" + sub)) {
      read_one(fields.get(), name, g + "/" + sub + "/" + name);
    }
  };
  std::size_t rows = 0;
  for_each_field("scalars", [&](hid_t loc, const std::string& name, const std::string& object) {
    frame.scalars[name] = c.read<double>(loc, name, object, H5T_NATIVE_DOUBLE, 1, 0, rows);
    check_rows(object, rows);
  });
  for_each_field("vectors", [&](hid_t loc, const std::string& name, const std::string& object) {
    frame.vectors[name] =
        unflatten(c.read<double>(loc, name, object, H5T_NATIVE_DOUBLE, 2, 3, rows));
    check_rows(object, rows);
  });
  for_each_field("labels", [&](hid_t loc, const std::string& name, const std::string& object) {
    frame.labels[name] = c.read<int>(loc, name, object, H5T_NATIVE_INT, 1, 0, rows);
    check_rows(object, rows);
  });
  if (c.exists(group.get(), "segments", g + "/segments")) {
    std::vector<int> flat =
        c.read<int>(group.get(), "segments", g + "/segments", H5T_NATIVE_INT, 2, 2, rows);
    frame.segments.resize(rows);
    for (std::size_t i = 0; i < rows; ++i) frame.segments[i] = {flat[2 * i], flat[2 * i + 1]};
  }
  return frame;
}

std::vector<Series> read_series(const std::filesystem::path& h5_path) {
  Handle file = open_for_reading(h5_path);
  const Checker c{h5_path};
  std::vector<Series> all;
  if (!c.exists(file.get(), "series", "/series")) return all;
  Handle group = c.open_group(file.get(), "/series", "/series");
  for (const auto& name : c.children(group.get(), "/series")) {
    const std::string g = "/series/" + name;
    Handle one = c.open_group(group.get(), name, g);
    Series series;
    series.name = name;
    std::size_t rows = 0, value_rows = 0;
    series.times = c.read<double>(one.get(), "time", g + "/time", H5T_NATIVE_DOUBLE, 1, 0, rows);
    series.values =
        c.read<double>(one.get(), "values", g + "/values", H5T_NATIVE_DOUBLE, 1, 0, value_rows);
    // A killed writer may have extended one of the two by a sample: keep the common part.
    const std::size_t common = std::min(rows, value_rows);
    series.times.resize(common);
    series.values.resize(common);
    {
      Handle values = c.id(H5Dopen2(one.get(), "values", H5P_DEFAULT), H5Dclose, g + "/values",
                           "opening dataset");
      series.info.unit = c.read_string(values.get(), "unit", g + "/values");
      series.info.description = c.read_string(values.get(), "description", g + "/values");
    }
    series.info.reference_source = c.read_string(one.get(), "reference_source", g);
    if (c.exists(one.get(), "reference_time", g + "/reference_time")) {
      series.info.reference_times = c.read<double>(
          one.get(), "reference_time", g + "/reference_time", H5T_NATIVE_DOUBLE, 1, 0, rows);
      series.info.reference_values =
          c.read<double>(one.get(), "reference_values", g + "/reference_values", H5T_NATIVE_DOUBLE,
                         1, 0, value_rows);
      const std::size_t reference_common = std::min(rows, value_rows);
      series.info.reference_times.resize(reference_common);
      series.info.reference_values.resize(reference_common);
    }
    all.push_back(std::move(series));
  }
  return all;
}

FieldInfo read_field_info(const std::filesystem::path& h5_path, const std::string& dataset) {
  Handle file = open_for_reading(h5_path);
  const Checker c{h5_path};
  Handle dset = c.id(H5Dopen2(file.get(), dataset.c_str(), H5P_DEFAULT), H5Dclose, dataset,
                     "opening dataset");
  return FieldInfo{c.read_string(dset.get(), "unit", dataset),
                   c.read_string(dset.get(), "description", dataset),
                   c.read_string(dset.get(), "legend", dataset)};
}

}  // namespace cosim::output
