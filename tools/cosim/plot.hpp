// Figures with matplotlib: cosim writes what to draw as JSON and runs tools/cosim_plot.py
// (copied beside the cosim executable) with a python3 that has matplotlib.
#pragma once

#include <filesystem>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>
#include <vector>

namespace cosim::tool {

// Plotting is unavailable (no python3, no matplotlib) or the script failed.
struct PlotError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// The interpreter to draw with: COSIM_PYTHON when set (and only it), else python3 on the PATH,
// then /usr/bin/python3 (Debian's, where python3-matplotlib installs), the first that imports
// matplotlib. Throws PlotError saying what each candidate lacked.
std::string plotting_python();

// Draws {"figures": [...]} (see tools/cosim_plot.py); throws PlotError.
void draw_figures(const nlohmann::json& figures);

// `cosim plot`: a figure per metric that has a time series of its name in the participant's
// HDF5 output (series, its reference curve, the reference value and the reported value), and
// one overview figure of every series per HDF5 file; PNGs in the run folder. Returns them;
// metrics without a series are listed in `notes`.
std::vector<std::filesystem::path> plot_run(const std::filesystem::path& run_dir,
                                            std::vector<std::string>& notes);

}  // namespace cosim::tool
