// The point-series writer: frames, series and their XDMF index (hdf5_access.hpp checks every
// HDF5 call).
#include "cosim/output/point_series.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <set>
#include <stdexcept>
#include <utility>

#include "hdf5_access.hpp"
#include "xdmf.hpp"

namespace cosim::output {

using detail::Checker;
using detail::flatten;
using detail::frame_group;
using detail::Handle;
using detail::silence_hdf5;

namespace {

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

// What the writer's own datasets mean; fields fall back to a description naming them.
FieldInfo completed(FieldInfo info, const std::string& default_unit,
                    const std::string& default_description) {
  if (info.unit.empty()) info.unit = default_unit;
  if (info.description.empty()) info.description = default_description;
  return info;
}

constexpr const char* kUnspecified = "unspecified";
constexpr double kNotComputed = std::numeric_limits<double>::quiet_NaN();
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
      // NaN marks a value the solver does not compute for that point (e.g. the number density
      // of a fluid's dummy particles): the statistics are over the points that have one, and
      // NaN only when none has.
      double sum = 0.0, low = kNotComputed, high = kNotComputed;
      std::size_t computed = 0;
      for (double v : values) {
        if (std::isnan(v)) continue;
        low = computed == 0 ? v : std::min(low, v);
        high = computed == 0 ? v : std::max(high, v);
        sum += v;
        ++computed;
      }
      const double mean = computed > 0 ? sum / static_cast<double>(computed) : kNotComputed;
      const std::string prefix = kFramePrefix + name;
      const std::string over =
          " over the frame's points that have a value (NaN: not computed) of: ";
      append_frame_series(index, prefix + "_min", low,
                          {field.unit, "smallest" + over + field.description, ""});
      append_frame_series(index, prefix + "_max", high,
                          {field.unit, "largest" + over + field.description, ""});
      append_frame_series(index, prefix + "_mean", mean,
                          {field.unit, "mean" + over + field.description, ""});
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

}  // namespace cosim::output
