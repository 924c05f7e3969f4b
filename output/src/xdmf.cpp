#include "xdmf.hpp"

#include "cosim/output/files.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <stdexcept>
#include <system_error>

namespace cosim::output::detail {
namespace {

// Shortest text that reads back to the same double, so Time values match the HDF5 attribute.
std::string format_double(double value) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.17g", value);
  return buffer;
}

struct Writer {
  std::string out;
  std::string h5_name;
  const std::vector<SeriesIndex>* series = nullptr;

  void line(int depth, const std::string& text) {
    out.append(static_cast<std::size_t>(depth) * 2, ' ');
    out += text;
    out += '\n';
  }

  void data_item(int depth, const std::string& dims, const char* number_type, int precision,
                 const std::string& dataset) {
    line(depth, "<DataItem Dimensions=\"" + dims + "\" NumberType=\"" + number_type +
                    "\" Precision=\"" + std::to_string(precision) + "\" Format=\"HDF\">" +
                    xml_escape(h5_name) + ":" + xml_escape(dataset) + "</DataItem>");
  }

  void attribute(int depth, const std::string& name, const char* type, const std::string& dims,
                 const char* number_type, int precision, const std::string& dataset) {
    line(depth, "<Attribute Name=\"" + xml_escape(name) + "\" AttributeType=\"" + type +
                    "\" Center=\"Node\">");
    data_item(depth + 1, dims, number_type, precision, dataset);
    line(depth, "</Attribute>");
  }

  // Geometry and point attributes are shared by the point grid and the segment grid.
  void geometry_and_attributes(int depth, const FrameIndex& f) {
    const std::string n = std::to_string(f.points);
    line(depth, "<Geometry GeometryType=\"XYZ\">");
    data_item(depth + 1, n + " 3", "Float", 8, f.group + "/positions");
    line(depth, "</Geometry>");
    for (const auto& name : f.scalars) {
      attribute(depth, name, "Scalar", n, "Float", 8, f.group + "/scalars/" + name);
    }
    for (const auto& name : f.vectors) {
      attribute(depth, name, "Vector", n + " 3", "Float", 8, f.group + "/vectors/" + name);
    }
    for (const auto& name : f.labels) {
      attribute(depth, name, "Scalar", n, "Int", 4, f.group + "/labels/" + name);
    }
  }

  // One value for the whole grid: ParaView's field data, which "Plot Data Over Time" draws.
  void grid_value(int depth, const std::string& name, double value) {
    if (!std::isfinite(value)) return;  // not every XML reader parses "nan"
    line(depth,
         "<Attribute Name=\"" + xml_escape(name) + "\" AttributeType=\"Scalar\" Center=\"Grid\">");
    line(depth + 1,
         "<DataItem Dimensions=\"1\" NumberType=\"Float\" Precision=\"8\" Format=\"XML\">" +
             format_double(value) + "</DataItem>");
    line(depth, "</Attribute>");
  }

  void point_grid(int depth, const std::string& name, const FrameIndex& f) {
    const std::string n = std::to_string(f.points);
    line(depth, "<Grid Name=\"" + name + "\" GridType=\"Uniform\">");
    line(depth + 1, "<Time Value=\"" + format_double(f.time) + "\"/>");
    // Explicit connectivity: without it the Xdmf3 readers make no cells at all.
    line(depth + 1, "<Topology TopologyType=\"Polyvertex\" NumberOfElements=\"" + n +
                        "\" NodesPerElement=\"1\">");
    data_item(depth + 2, n, "Int", 4, f.topology);
    line(depth + 1, "</Topology>");
    geometry_and_attributes(depth + 1, f);
    for (const auto& [value_name, value] : f.grid_values) grid_value(depth + 1, value_name, value);
    if (series != nullptr) {
      for (const auto& s : *series) {
        double value = 0.0;
        if (sample_at(s, f.time, value)) grid_value(depth + 1, s.name, value);
      }
    }
    line(depth, "</Grid>");
  }

  void segment_grid(int depth, const FrameIndex& f) {
    const std::string m = std::to_string(f.segments);
    line(depth, "<Grid Name=\"segments\" GridType=\"Uniform\">");
    line(depth + 1, "<Time Value=\"" + format_double(f.time) + "\"/>");
    line(depth + 1, "<Topology TopologyType=\"Polyline\" NumberOfElements=\"" + m +
                        "\" NodesPerElement=\"2\">");
    data_item(depth + 2, m + " 2", "Int", 4, f.group + "/segments");
    line(depth + 1, "</Topology>");
    geometry_and_attributes(depth + 1, f);
    line(depth, "</Grid>");
  }
};

}  // namespace

bool sample_at(const SeriesIndex& series, double time, double& value) {
  const auto& t = series.times;
  if (t.empty() || t.size() != series.values.size()) return false;
  const double tolerance = 1e-9 * std::max(1.0, std::abs(time));
  if (time < t.front() - tolerance || time > t.back() + tolerance) return false;
  // First sample at or after `time` (within round-off); samples are in time order.
  const auto after = std::lower_bound(t.begin(), t.end(), time - tolerance);
  if (after == t.end()) {
    value = series.values.back();
    return true;
  }
  const auto i = static_cast<std::size_t>(after - t.begin());
  if (std::abs(t[i] - time) <= tolerance || i == 0) {
    value = series.values[i];
    return true;
  }
  const double w = (time - t[i - 1]) / (t[i] - t[i - 1]);
  value = series.values[i - 1] + w * (series.values[i] - series.values[i - 1]);
  return true;
}

std::string xml_escape(const std::string& text) {
  std::string out;
  out.reserve(text.size());
  for (char c : text) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      case '\'':
        out += "&apos;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

std::string render_xdmf(const std::string& title, const std::string& h5_name,
                        const std::vector<FrameIndex>& frames,
                        const std::vector<SeriesIndex>& series) {
  Writer w;
  w.h5_name = h5_name;
  w.series = &series;
  w.line(0, "<?xml version=\"1.0\" encoding=\"utf-8\"?>");
  w.line(0, "<Xdmf xmlns:xi=\"http://www.w3.org/2001/XInclude\" Version=\"3.0\">");
  w.line(1, "<Domain>");
  w.line(2, "<Grid Name=\"" + xml_escape(title) +
                "\" GridType=\"Collection\" CollectionType=\"Temporal\">");
  // One cell type per Uniform grid, so a chain frame is a spatial collection of the point
  // cloud and its polylines over the same nodes. The legacy Xdmf reader fixes its output type
  // at the first time step and shows nothing in steps of another type: once any frame has
  // segments, every frame is a spatial collection (some with the points only).
  const bool collections = std::any_of(frames.begin(), frames.end(), [](const FrameIndex& f) {
    return f.points > 0 && f.segments > 0;
  });
  for (const auto& f : frames) {
    // Readers reject zero-sized HDF5 data items, so empty frames stay in HDF5 only.
    if (f.points == 0) continue;
    const std::string name = "frame_" + f.group.substr(f.group.rfind('/') + 1);
    if (!collections) {
      w.point_grid(3, name, f);
      continue;
    }
    w.line(3, "<Grid Name=\"" + name + "\" GridType=\"Collection\" CollectionType=\"Spatial\">");
    w.line(4, "<Time Value=\"" + format_double(f.time) + "\"/>");
    w.point_grid(4, "points", f);
    if (f.segments > 0) w.segment_grid(4, f);
    w.line(3, "</Grid>");
  }
  w.line(2, "</Grid>");
  w.line(1, "</Domain>");
  w.line(0, "</Xdmf>");
  return w.out;
}

void write_file_atomically(const std::filesystem::path& path, const std::string& content) {
  try {
    output::write_file_atomically(path, content);
  } catch (const std::runtime_error& error) {
    throw std::runtime_error(std::string("cosim_output: ") + error.what());
  }
}

}  // namespace cosim::output::detail
