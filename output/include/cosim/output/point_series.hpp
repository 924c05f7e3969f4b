// Time series of point clouds (particles, plant nodes, DEM elements) in HDF5, with an XDMF
// index that ParaView opens directly. Also reads frames back for restarts.
#pragma once

#include <Eigen/Core>
#include <array>
#include <filesystem>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace cosim::output {

// One snapshot. All per-point arrays have positions.size() entries.
struct PointFrame {
  double time = 0.0;
  std::vector<Eigen::Vector3d> positions;
  std::map<std::string, std::vector<double>> scalars;           // e.g. "pressure"
  std::map<std::string, std::vector<Eigen::Vector3d>> vectors;  // e.g. "velocity"
  std::map<std::string, std::vector<int>> labels;               // e.g. "kind", "plant"
  // Optional line segments between points (plant chains); empty means a plain point cloud.
  std::vector<std::array<int, 2>> segments;
};

// Writes <stem>.h5 and <stem>.xmf. The XDMF file is rewritten after every frame so a run that
// stops early is still viewable up to its last frame.
class PointSeriesWriter {
 public:
  PointSeriesWriter(const std::filesystem::path& stem, std::string title);
  ~PointSeriesWriter();
  PointSeriesWriter(const PointSeriesWriter&) = delete;
  PointSeriesWriter& operator=(const PointSeriesWriter&) = delete;

  void write_frame(const PointFrame& frame);
  // Named scalar time series (tip deflection, front position, ...) stored under /series/<name>.
  void write_series(const std::string& name, const std::vector<double>& times,
                    const std::vector<double>& values);
  int frame_count() const;
  std::filesystem::path h5_path() const;
  std::filesystem::path xdmf_path() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// Reads frame `index` (negative counts from the end: -1 is the last frame).
PointFrame read_point_frame(const std::filesystem::path& h5_path, int index);
int count_point_frames(const std::filesystem::path& h5_path);

}  // namespace cosim::output
