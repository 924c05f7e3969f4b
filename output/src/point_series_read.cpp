// Reading point series back: frame counts, frames by index or time, series, field metadata.
#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "cosim/output/point_series.hpp"
#include "hdf5_access.hpp"

namespace cosim::output {

using detail::Checker;
using detail::frame_group;
using detail::frames_in;
using detail::Handle;
using detail::open_for_reading;
using detail::unflatten;

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
