// HDF5 side of the point series. Every HDF5 call is checked; failures become exceptions that
// name the file and the object, with HDF5's own innermost message appended.
#include "cosim/output/point_series.hpp"

#include <hdf5.h>

#include <cstdio>
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

std::string hdf5_message() {
  std::string message;
  H5Ewalk2(H5E_DEFAULT, H5E_WALK_UPWARD, take_innermost, &message);
  H5Eclear2(H5E_DEFAULT);
  return message.empty() ? std::string() : " (" + message + ")";
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

  void write(hid_t loc, const std::string& name, const std::string& object, hid_t file_type,
             hid_t mem_type, const std::vector<hsize_t>& dims, const void* data) const {
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

}  // namespace

struct PointSeriesWriter::Impl {
  std::filesystem::path h5;
  std::filesystem::path xmf;
  std::string title;
  Handle file;
  std::vector<detail::FrameIndex> frames;

  Checker checker() const { return Checker{h5}; }
  void write_xdmf() const {
    detail::write_file_atomically(xmf, detail::render_xdmf(title, h5.filename().string(), frames));
  }
  void flush() const { checker().ok(H5Fflush(file.get(), H5F_SCOPE_GLOBAL), "/", "flushing"); }
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
  c.create_group(impl_->file.get(), "/frames", "/frames");
  c.create_group(impl_->file.get(), "/series", "/series");
  impl_->flush();
  // Replaces any index left by an earlier run that would now point at missing frames.
  impl_->write_xdmf();
}

PointSeriesWriter::~PointSeriesWriter() = default;

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

  try {
    Handle group = c.create_group(file, g, g);
    {
      Handle space = c.id(H5Screate(H5S_SCALAR), H5Sclose, g + "@time", "creating dataspace for");
      Handle attr = c.id(
          H5Acreate2(group.get(), "time", H5T_IEEE_F64LE, space.get(), H5P_DEFAULT, H5P_DEFAULT),
          H5Aclose, g + "@time", "creating attribute");
      c.ok(H5Awrite(attr.get(), H5T_NATIVE_DOUBLE, &frame.time), g + "@time", "writing attribute");
    }
    c.write(group.get(), "positions", g + "/positions", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, {n, 3},
            flatten(frame.positions).data());

    Handle scalars = c.create_group(group.get(), "scalars", g + "/scalars");
    for (const auto& [name, values] : frame.scalars) {
      c.write(scalars.get(), name, g + "/scalars/" + name, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, {n},
              values.data());
      index.scalars.push_back(name);
    }
    Handle vectors = c.create_group(group.get(), "vectors", g + "/vectors");
    for (const auto& [name, values] : frame.vectors) {
      c.write(vectors.get(), name, g + "/vectors/" + name, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE,
              {n, 3}, flatten(values).data());
      index.vectors.push_back(name);
    }
    Handle labels = c.create_group(group.get(), "labels", g + "/labels");
    for (const auto& [name, values] : frame.labels) {
      c.write(labels.get(), name, g + "/labels/" + name, H5T_STD_I32LE, H5T_NATIVE_INT, {n},
              values.data());
      index.labels.push_back(name);
    }
    if (!frame.segments.empty()) {
      // std::array<int, 2> is two contiguous ints, so the vector is already an M x 2 block.
      static_assert(sizeof(std::array<int, 2>) == 2 * sizeof(int));
      c.write(group.get(), "segments", g + "/segments", H5T_STD_I32LE, H5T_NATIVE_INT,
              {static_cast<hsize_t>(frame.segments.size()), 2}, frame.segments.data());
    }
  } catch (...) {
    // Drop the partial group so the frame numbering and readers stay consistent.
    H5Ldelete(file, g.c_str(), H5P_DEFAULT);
    H5Eclear2(H5E_DEFAULT);
    throw;
  }
  impl_->flush();
  impl_->frames.push_back(std::move(index));
  // Index after the data is on disk, so the .xmf never references a missing frame.
  impl_->write_xdmf();
}

void PointSeriesWriter::write_series(const std::string& name, const std::vector<double>& times,
                                     const std::vector<double>& values) {
  check_name(name, "series");
  if (times.size() != values.size()) {
    throw std::invalid_argument("cosim_output: series '" + name + "' has " +
                                std::to_string(times.size()) + " times but " +
                                std::to_string(values.size()) + " values");
  }
  const Checker c = impl_->checker();
  const std::string g = "/series/" + name;
  Handle series = c.open_group(impl_->file.get(), "/series", "/series");
  // HDF5 datasets have fixed size here, so a rewrite replaces the whole group.
  if (c.exists(series.get(), name, g)) {
    c.ok(H5Ldelete(series.get(), name.c_str(), H5P_DEFAULT), g, "deleting");
  }
  Handle group = c.create_group(series.get(), name, g);
  const std::vector<hsize_t> dims{static_cast<hsize_t>(times.size())};
  c.write(group.get(), "time", g + "/time", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, dims, times.data());
  c.write(group.get(), "values", g + "/values", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, dims,
          values.data());
  impl_->flush();
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
  {
    Handle attr =
        c.id(H5Aopen(group.get(), "time", H5P_DEFAULT), H5Aclose, g + "@time", "opening attribute");
    c.ok(H5Aread(attr.get(), H5T_NATIVE_DOUBLE, &frame.time), g + "@time", "reading attribute");
  }
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

}  // namespace cosim::output
