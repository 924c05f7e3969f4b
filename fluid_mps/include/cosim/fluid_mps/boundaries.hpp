// Open boundaries of seed 001 section 2.2: thin partition walls (1), soluble moving wall inflow
// with automatic water-level control and free outflow with particle recycling (3). The periodic
// boundary (4) lives in FluidSystem itself (MpsParameters::periodic).
#pragma once

#include <Eigen/Core>
#include <limits>
#include <vector>

#include "cosim/fluid_mps/fluid_system.hpp"
#include "cosim/fluid_mps/neighbour_grid.hpp"
#include "cosim/fluid_mps/parameters.hpp"

namespace cosim::mps {

// A flume's outlet: fluid particles past x = outlet_x leave the flow, as water running off the
// end of a flume does. They become inactive (velocity 0, out of every operator, slot kept where
// they are, never checked for escape). Returns how many left in this call.
int remove_fluid_beyond(FluidSystem& system, double outlet_x);

// Seed 001 section 2.2(1): drops the pairs (i, j) whose connecting segment crosses a partition
// segment (strictly opposite sides; a pair passing exactly over a segment end is dropped too).
// Only particles within the list radius of a segment are tested. Keeps the order, so loops over
// the list stay deterministic. `periodic` gives the minimum-image partner position.
// `kinds` (optional) enables PartitionSegment::keep_walls; without it every crossing pair goes.
void remove_partition_crossings(NeighbourList& list, const std::vector<Eigen::Vector3d>& positions,
                                const std::vector<PartitionSegment>& partitions,
                                const PeriodicBoundary& periodic = PeriodicBoundary{},
                                const std::vector<ParticleKind>* kinds = nullptr);

// The same test without removal: crossing pairs get an infinite distance, so every operator skips
// them while the list keeps its layout (the fluid step's list is kept over several steps).
void mask_partition_crossings(NeighbourList& list, const std::vector<Eigen::Vector3d>& positions,
                              const std::vector<PartitionSegment>& partitions,
                              const PeriodicBoundary& periodic = PeriodicBoundary{},
                              const std::vector<ParticleKind>* kinds = nullptr);
// True if the segment p-q crosses the partition segment (2D, x-y plane).
bool crosses_partition(const Eigen::Vector3d& p, const Eigen::Vector3d& q,
                       const PartitionSegment& segment);

// Settings of the soluble moving wall inflow (Gotoh et al., seed 001 section 2.2(3)) and of the
// free outflow. Geometry: flow along +x, inflow line x = inflow_x, bed surface at the height
// bed_height along the vertical, which is y in 2D and z in 3D ("height" below means that
// coordinate). In 3D the channel runs across y from 0 to `width` between side walls.
struct OpenBoundarySettings {
  double inflow_x = 0.0;
  double bed_height = 0.0;
  // 3D: the channel's width across y [m]; the block is the wall particles with 0 < y < width,
  // and a new column holds round(width / l0) particles across in each row. Unused in 2D.
  double width = 0.0;
  // Particles of the moving wall block: wall particles with x < inflow_x and a height above
  // bed_height at construction (in 3D also inside the width). Each column that passes inflow_x
  // dissolves: its lowest n rows (see control) become fluid with the wall velocity, the rest
  // return to the pool, and a new column of `block_rows` rows of wall particles (from the pool)
  // is added l0 behind the last column.
  int block_rows = 10;
  // How the inflow is set.
  //  velocity:  fixed wall velocity `velocity` and `inflow_rows` rows per column;
  //  discharge: seed 001's automatic level adjustment: at each dissolution the water level h
  //             just downstream of inflow_x is measured (see level_measure); the next
  //             column releases n = round(h / l0) rows (1..block_rows) and the wall moves at
  //             U = discharge / (n l0), so the discharge per width stays `discharge`;
  //  level:     keeps the level at `target_level`: n = round(target_level / l0) rows and an
  //             integral controller dU/dt = level_gain (target_level - h), U in
  //             [min_velocity, max_velocity].
  enum class Control { velocity, discharge, level };
  Control control = Control::discharge;
  double velocity = 0.1;  // [m/s]; initial value for discharge / level control
  int inflow_rows = 5;
  double discharge = 0.0;     // q per unit width [m^2/s] (in 3D the whole inflow is q width)
  double target_level = 0.0;  // [m] above bed_height
  // Level measurement window [inflow_x + level_offset, + level_window] (defaults 2 l0 and 8 l0;
  // seed 001 uses a short section of 3 % of its domain length). mean_depth: fluid area in the
  // window / window length, in 3D fluid volume / (window length x width) (default: unbiased,
  // smooth); highest: highest fluid particle + l0/2
  // (seed 001's choice; splashes bias it upwards and the just-released column dominates it).
  enum class LevelMeasure { mean_depth, highest };
  LevelMeasure level_measure = LevelMeasure::mean_depth;
  double level_offset = -1.0;  // [m]; < 0: 2 l0
  double level_window = 0.0;   // [m]; <= 0: 8 l0
  double level_gain = 1.0;     // [1/s^2]: dU/dt per metre of level error
  double min_velocity = 0.0;
  double max_velocity = 2.0;
  // Soft start: the wall speed rises linearly from 0 at t = 0 to full at ramp_time [s] (0: none).
  // A wall started impulsively into still water throws up a spout at high inflows.
  double ramp_time = 0.0;
  // Free outflow: fluid particles with x > outflow_x or a height below outflow_min_height leave the
  // flow and are kept in the pool (kind inactive, velocity 0) for the inflow to reuse (seed 001
  // section 2.2(3)).
  double outflow_x = std::numeric_limits<double>::infinity();
  double outflow_min_height = -std::numeric_limits<double>::infinity();
};

// Result of one OpenBoundaries::update.
struct BoundaryUpdate {
  int dissolved = 0;  // wall particles turned into fluid
  int recycled = 0;   // fluid particles removed at the outflow
  int created = 0;    // wall particles taken from the pool for new block columns
};

// The running state of an OpenBoundaries that its particles do not hold (the block and the pool
// are re-derived from their kinds), kept in this one record: what a checkpoint carries so that a
// restarted run releases the same columns at the same times as the uninterrupted one. Plain
// values, written as bytes.
struct OpenBoundaryState {
  double velocity = 0.0;               // [m/s] the control's wall speed
  double level = 0.0;                  // [m] the last measured level
  double last_dissolution_time = 0.0;  // [s]
  long dissolved_total = 0, recycled_total = 0;
  long rows = 0;  // released per column (long: no padding bytes in the record)
};

// Call update() after every FluidSystem::step. The particle count never changes; the pool is the
// set of inactive particles (lowest index first, so runs are deterministic and restartable: a
// restarted system gives the same block and pool; restore() brings back the rest).
class OpenBoundaries {
 public:
  OpenBoundaries(FluidSystem& system, OpenBoundarySettings settings);

  BoundaryUpdate update();

  // Current wall (inflow) velocity without the soft start [m/s]; the wall moves at wall_speed().
  double velocity() const { return state_.velocity; }
  double wall_speed() const;
  int inflow_rows() const { return static_cast<int>(state_.rows); }
  double measured_level() const { return state_.level; }  // last level above bed_height [m]
  long dissolved_total() const { return state_.dissolved_total; }
  long recycled_total() const { return state_.recycled_total; }
  // Fluid volume (area in 2D) released at the inflow so far [m^3, m^2 in 2D]: l0^d a particle.
  double inflow_volume() const;
  int pool_size() const;
  const std::vector<int>& block() const { return block_; }
  const OpenBoundarySettings& settings() const { return settings_; }

  const OpenBoundaryState& state() const { return state_; }
  // Takes over a state saved by state() (of the same scene), and moves the block at its speed.
  void restore(const OpenBoundaryState& state);

 private:
  int take_from_pool();
  void set_block_velocity();
  double height(const Eigen::Vector3d& x) const { return x[up_]; }
  // The fluid volume of `particles` lattice cells, l0^dimension each [m^3, m^2 in 2D].
  double volume_of(double particles) const;
  // Adds one new block column at x (every row, and in 3D every position across the width).
  void add_column(double x, BoundaryUpdate& result);

  FluidSystem& system_;
  OpenBoundarySettings settings_;
  int up_ = 1;      // the vertical axis: y in 2D, z in 3D
  int across_ = 1;  // particles across the width in a row (1 in 2D)
  std::vector<int> block_;
  OpenBoundaryState state_;
  int pool_cursor_ = 0;
};

// Outlet of an open channel (seed 000 section 4: "from the downstream end of the vegetation a
// level bed 2.0 m long, then a 1:1 adverse slope"; the seed gives no height for the slope): from
// x = length a bed `flat_length` long that is level in the world, so it rises against the tilted
// channel bed by tan(theta), theta from the gravity tilt; then a slope rising 1:1 in the world to
// `slope_height` above that bed; the water leaves over its crest in a free overfall (the solid
// ends there in a vertical face). Both zero: the channel bed ends at x = length in a free
// overfall.
struct ChannelOutlet {
  double flat_length = 0.0;   // [m], measured level in the world
  double slope_height = 0.0;  // [m], of the crest above the level bed, in the world's vertical
  bool empty() const { return flat_length <= 0.0 && slope_height <= 0.0; }
};

// Scene: open channel with a soluble moving wall inflow (seed 001 section 2.2(3)). Bed top at
// y = 0 from x = -(block_columns + 2) l0 to x = length (free overfall at x = length, or the
// `outlet` beyond it, whose solid cells get walls and dummies as the fishway's); inflow line
// at x = 0; a block of block_columns x block_rows wall particles just upstream of it; still water
// of `initial_depth` on x in [0, length]; `pool_particles` inactive particles parked under the
// outlet. Fills parameters.domain if empty and `settings` (inflow_x = 0, bed_height = 0,
// block_rows, outflow_x = length + 3 l0, outflow_min_height = -(layers + 4) l0). slope = sin(theta)
// tilts gravity as in periodic_channel. With an outlet the still water fills its open cells to the
// same initial depth and the outflow line lies 3 l0 beyond the crest.
ParticleSet open_channel(MpsParameters& parameters, OpenBoundarySettings& settings, double length,
                         double initial_depth, double block_height, int block_columns = 4,
                         int pool_particles = 400, int wall_layers = 2, int dummy_layers = 2,
                         double slope = 0.0, const ChannelOutlet& outlet = {});

// The crest of an open channel's outlet (x, y in the channel's frame) [m]: (length, 0) without
// one. Gravity as open_channel leaves it (tilted).
Eigen::Vector3d outlet_crest(const MpsParameters& parameters, double length,
                             const ChannelOutlet& outlet);

// Scene: periodic open channel (seed 000 section 3.1, seed 001 section 2.2(4)): x in [0, length)
// periodic, still water of `depth` over a bed of wall + dummy layers. slope = sin(theta) tilts
// gravity, g = |g| (sin theta, -cos theta); driving_pressure_drop is left to the caller.
// Enables parameters.periodic and fills parameters.domain if empty.
ParticleSet periodic_channel(MpsParameters& parameters, double length, double depth,
                             double slope = 0.0, int wall_layers = 2, int dummy_layers = 2);

// A straight 3D channel's cross-section and walls (x along the flow, y across, z up, the bed
// slope in the world's gravity): the bed z < 0 and side walls y < 0 and y > width, each
// wall_layers of wall and dummy_layers of dummy particles on the cubic lattice of cells l0
// wide; the side walls reach wall_height above the bed.
struct Channel3d {
  double width = 0;        // between the side walls [m]
  double wall_height = 0;  // of the side walls above the bed [m]
  int wall_layers = 2, dummy_layers = 2;
};

// Scene: periodic_channel in 3D: x in [0, length) periodic, still water `depth` deep across
// the whole width. Enables parameters.periodic and fills parameters.domain if empty.
ParticleSet periodic_channel_3d(MpsParameters& parameters, const Channel3d& channel, double length,
                                double depth);

// Scene: open_channel in 3D: as open_channel, the bed and side walls from
// x = -(block_columns + 2) l0 to x = length (a free overfall there), a block of block_columns
// columns of block_height rows across the whole width just upstream of x = 0, still water of
// initial_depth on x in [0, length), and pool_particles parked below the overfall. Fills
// parameters.domain if empty and `settings` (inflow_x = 0, bed_height = 0, width, block_rows,
// outflow_x = length + 3 l0, outflow_min_height = -(layers + 4) l0).
ParticleSet open_channel_3d(MpsParameters& parameters, OpenBoundarySettings& settings,
                            const Channel3d& channel, double length, double initial_depth,
                            double block_height, int block_columns = 4, int pool_particles = 4000);

}  // namespace cosim::mps
