// XDMF index over the HDF5 frames: internal to cosim_output.
#pragma once

#include <cstddef>
#include <filesystem>
#include <string>
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
};

// XDMF 3 temporal collection. `h5_name` is the HDF5 file name relative to the .xmf.
std::string render_xdmf(const std::string& title, const std::string& h5_name,
                        const std::vector<FrameIndex>& frames);

// Writes to a sibling temporary file and renames it over `path`, so a reader (or a killed run)
// never sees a half-written index.
void write_file_atomically(const std::filesystem::path& path, const std::string& content);

std::string xml_escape(const std::string& text);

}  // namespace cosim::output::detail
