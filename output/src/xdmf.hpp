// XDMF index over the HDF5 frames: internal to cosim_output.
#pragma once

#include <cstddef>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

namespace cosim::output::detail {

// What the XDMF needs to know about one frame already written to HDF5.
struct FrameIndex {
  std::string group;  // e.g. "/frames/000003"
  double time = 0.0;
  std::size_t points = 0;
  std::size_t segments = 0;
  std::vector<std::string> scalars;
  std::vector<std::string> vectors;
  std::vector<std::string> labels;
  std::string
      topology;  // the dataset of its Polyvertex connectivity, e.g. "/topology/polyvertex_9"
  // Values of the frame as a whole (its statistics), shown as grid (field) data.
  std::vector<std::pair<std::string, double>> grid_values;
};

// A series written by the caller, shown in each frame at the frame's time.
struct SeriesIndex {
  std::string name;
  std::vector<double> times;
  std::vector<double> values;
};

// The series' value at `time`: linear between samples, a sample itself within round-off; none
// outside the sampled interval.
bool sample_at(const SeriesIndex& series, double time, double& value);

// XDMF 3 temporal collection. `h5_name` is the HDF5 file name relative to the .xmf. Points are
// Polyvertex cells with explicit connectivity (the legacy Xdmf and the Xdmf3 readers of ParaView
// both make one vertex cell per point from it); grid values and series are Grid-centred
// attributes, which ParaView shows as field data.
std::string render_xdmf(const std::string& title, const std::string& h5_name,
                        const std::vector<FrameIndex>& frames,
                        const std::vector<SeriesIndex>& series = {});

// Writes to a sibling temporary file and renames it over `path`, so a reader (or a killed run)
// never sees a half-written index.
void write_file_atomically(const std::filesystem::path& path, const std::string& content);

std::string xml_escape(const std::string& text);

}  // namespace cosim::output::detail
