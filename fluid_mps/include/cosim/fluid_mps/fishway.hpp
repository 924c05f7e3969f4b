// Pool-type fishway scenes of seed 001 (Maeno et al.): a stepped chain of pools separated by
// thin partition walls (weirs), fed by a soluble moving wall and drained by a free overfall, and
// one pool with a periodic boundary; weir gauges measure the discharge over each crest and the
// head upstream of it, for the mass balance and the sharp-crested weir equation.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "cosim/fluid_mps/boundaries.hpp"
#include "cosim/fluid_mps/fluid_system.hpp"
#include "cosim/fluid_mps/parameters.hpp"

namespace cosim::mps {

// Seed 001 fig. 2.1 gives its geometry only as a drawing (three pools, 5229 particles at
// l0 = 6.66 mm); these dimensions are ours, of the same size.
struct FishwayGeometry {
  int pools = 3;
  double pool_length = 0.3;     // crest to crest [m]
  double step_height = 0.05;    // floor drop from one pool to the next [m]
  double weir_height = 0.2;     // crest above the floor of the pool upstream of it [m]
  double orifice_height = 0.0;  // opening at the foot of every partition (seed 001: 2 cm) [m]
  double outlet_length = 0.1;   // apron after the last weir, then a free overfall [m]
  double block_height = 0.35;   // soluble moving wall above the first pool's floor [m]
  double initial_head = 0.0;    // pool_fishway: water starts this far above every crest [m]
  int block_columns = 4;
  int partition_columns = 2;  // wall particles across a partition
  int pool_particles = 3000;  // recycled particles for the inflow
};

// One weir: the vertical section through the crest and the head gauge upstream of it. The head
// is measured along `up` (minus gravity's direction) from the crest to the water surface at
// x = gauge_x, so a tilted-gravity (periodic) pool is measured correctly.
struct Weir {
  Eigen::Vector2d crest = Eigen::Vector2d::Zero();  // top of the partition (downstream face)
  double gauge_x = 0.0;
  double crest_height = 0.0;  // P: crest above the upstream pool floor [m]
  double floor = 0.0;         // y of the upstream pool floor
  double orifice_top = 0.0;   // y of the orifice top (= floor: no orifice)
};

// Stepped fishway: pool k has its floor at y = -k step_height over x in [k L, (k + 1) L); the
// partition closing pool k occupies the last `partition_columns` columns of the pool and rises
// to y = -k step_height + weir_height. Water fills every pool to initial_head above its crest
// (seed 001 starts at the crests; the weir head of the inflow shortens the filling). Fills
// `parameters.partitions` (one thin wall per weir, seed 001 section 2.2(1)), parameters.domain
// if empty, the inflow settings (the moving wall block stands at x < 0 in pool 0) and `weirs`.
ParticleSet pool_fishway(MpsParameters& parameters, OpenBoundarySettings& inflow,
                         const FishwayGeometry& geometry, std::vector<Weir>& weirs,
                         int wall_layers = 2, int dummy_layers = 2);

// One pool of the same fishway, periodic in x with a drop (seed 001 section 2.2(4), Run-OC):
// what spills over the partition re-enters at the pool's upstream end, one step higher, so the
// pool sees the pool above it upstream and the pool below it downstream. Water fills the pool to
// `fill_level` above its floor. Enables parameters.periodic (with drop = step), fills the
// partition, domain and `weirs` (one).
ParticleSet periodic_pool(MpsParameters& parameters, const FishwayGeometry& geometry,
                          double fill_level, std::vector<Weir>& weirs, int wall_layers = 2,
                          int dummy_layers = 2);

// Sharp-crested weir, per unit width: q = 2/3 C_d sqrt(2 g) h^{3/2} with Rehbock's
// C_d = 0.611 + 0.08 h / P (h head, P crest height above the upstream floor).
double rehbock_discharge(double head, double crest_height, double gravity);
// Head giving discharge q over the same weir (inverse of rehbock_discharge).
double rehbock_head(double discharge, double crest_height, double gravity);

// Time-averaged discharge over every weir crest and head upstream of it. The discharge through
// the crest section is the flux sum over the fluid particles in a band of width `band` centred
// on the crest line and above the crest: q = sum u . n l0^2 / band (n along the flow).
class WeirGauges {
 public:
  WeirGauges(std::vector<Weir> weirs, double band, double gauge_width);
  void record(const FluidSystem& system);
  int samples() const { return samples_; }
  std::size_t size() const { return weirs_.size(); }
  double mean_discharge(std::size_t weir) const;  // [m^2/s]
  double mean_head(std::size_t weir) const;       // [m]
  // Discharge through the orifice at the partition's foot (fluid in the band below orifice_top).
  double mean_orifice_discharge(std::size_t weir) const;
  const std::vector<Weir>& weirs() const { return weirs_; }
  // Instantaneous values of the last record() call.
  double discharge(std::size_t weir) const { return last_discharge_[weir]; }
  double head(std::size_t weir) const { return last_head_[weir]; }

 private:
  std::vector<Weir> weirs_;
  double band_, gauge_width_;
  std::vector<double> discharge_sum_, head_sum_, orifice_sum_, last_discharge_, last_head_;
  int samples_ = 0;
};

}  // namespace cosim::mps
