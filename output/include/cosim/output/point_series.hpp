// Time series of point clouds (particles, plant nodes, DEM elements) in HDF5, with an XDMF
// index that ParaView opens directly. Also reads frames and series back (restarts, plots).
//
// File layout (<stem>.h5):
//   /frames/NNNNNN            one group per frame, attribute `time` [s]
//     positions               N x 3
//     scalars/<name>          N
//     vectors/<name>          N x 3
//     labels/<name>           N, int32
//     segments                M x 2, int32 point indices (optional)
//   /topology/polyvertex_<N>  0..N-1, the vertex cells of every frame with N points (XDMF)
//   /series/<name>            time [s], values, optionally reference_time, reference_values
// Every dataset carries the string attributes `unit` and `description`; integer labels whose
// values are codes also carry `legend`.
#pragma once

#include <Eigen/Core>
#include <array>
#include <filesystem>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace cosim::output {

// What a stored array means. Empty members get defaults: unit "unspecified", a description
// naming the field.
struct FieldInfo {
  std::string unit;         // SI symbol ("m", "m/s", "Pa", "N"); "1" for dimensionless/indices
  std::string description;  // one line: what the value is
  std::string legend;       // integer codes only, e.g. "0 fluid, 1 wall, 2 dummy, 3 inactive"
};

// What a time series means and, optionally, the reference curve it is checked against.
struct SeriesInfo {
  std::string unit;
  std::string description;
  std::vector<double> reference_times;  // the reference curve, in the unit of the values
  std::vector<double> reference_values;
  std::string reference_source;  // where the reference comes from (paper, solution)
};

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

// A named time series as stored under /series/<name>.
struct Series {
  std::string name;
  std::vector<double> times;
  std::vector<double> values;
  SeriesInfo info;
};

// Writes <stem>.h5 and <stem>.xmf. The XDMF file is rewritten after every frame so a run that
// stops early is still viewable up to its last frame.
//
// Besides the series callers write, every frame appends to automatic series of the frame
// (names starting with "frame_"): its number of points, the minimum, maximum and mean of each
// scalar field, the largest magnitude of each vector field. Each frame of the XDMF carries, as
// grid (field) data, these values and every series value at the frame's time, so ParaView plots
// them over time.
class PointSeriesWriter {
 public:
  PointSeriesWriter(const std::filesystem::path& stem, std::string title);
  ~PointSeriesWriter();
  PointSeriesWriter(const PointSeriesWriter&) = delete;
  PointSeriesWriter& operator=(const PointSeriesWriter&) = delete;

  // Says what the field `name` (scalar, vector or label) means: its datasets in the frames
  // written from now on carry this unit, description and legend. Call before the first frame.
  void describe(const std::string& name, FieldInfo info);
  void write_frame(const PointFrame& frame);
  // Named scalar time series (tip deflection, front position, ...) stored under /series/<name>;
  // writing a name again replaces it. Names starting with "frame_" are the writer's own.
  void write_series(const std::string& name, const std::vector<double>& times,
                    const std::vector<double>& values, const SeriesInfo& info = {});
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
// The time [s] of frame `index` alone (no dataset is read).
double read_point_frame_time(const std::filesystem::path& h5_path, int index);
// The frame whose time is nearest to `time` [s], found by bisection (frames are written in time
// order; of two equally near, the later); -1 for a file without frames.
int nearest_point_frame(const std::filesystem::path& h5_path, double time);
// Every series of a file, by name; files without a /series group have none.
std::vector<Series> read_series(const std::filesystem::path& h5_path);
// The unit, description and legend attributes of one dataset, e.g. "/frames/000000/positions".
FieldInfo read_field_info(const std::filesystem::path& h5_path, const std::string& dataset);

}  // namespace cosim::output
