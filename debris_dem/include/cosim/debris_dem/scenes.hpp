// Scene builders for the flume and check-dam experiment of seed 004 (section 3, 4.1): the flume
// frame has x downstream along the bed, y across, z normal to the bed (bed at z = 0), and the
// slope enters through a tilted gravity vector.
#pragma once

#include <Eigen/Dense>
#include <vector>

#include "cosim/debris_dem/dem_world.hpp"

namespace cosim::dem {

// Gravity in the flume frame for a bed slope of slope_degrees (15 degrees in seed 004).
Eigen::Vector3d slope_gravity(double slope_degrees, double g = 9.81);

struct FlumeSpec {
  double x_start = 0.0;
  double length = 1.5;
  double width = 0.3;  // walls at y = 0 and y = width
  double wall_height = 0.15;
  bool upstream_wall = true;     // closes x = x_start
  bool downstream_wall = false;  // closes x = x_start + length (the water's tail pool, 3D fluid)
};
// Bed and side walls (and the end walls asked for) as triangles (two per rectangle); returns their
// element ids.
std::vector<int> add_flume(DemWorld& world, const FlumeSpec& spec, const Material& material);

// A box [lo, hi] closed by its floor (z = lo.z) and four side walls, open at the top (world z
// up), as fixed triangles (two per face); returns their element ids.
std::vector<int> add_open_box(DemWorld& world, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi,
                              const Material& material);

// Fixed roughness spheres on the bed, embedded by their radius (seed 004 fig. 12: 7-20 mm
// spheres), on a jittered grid of spacing ~ d_max over [x0, x1] x [0, width].
std::vector<int> add_bed_roughness(DemWorld& world, double x0, double x1, double width,
                                   double d_min, double d_max, unsigned seed,
                                   const Material& material);

struct GridDamSpec {
  double x = 1.0;                  // streamwise position of the column axes
  double width = 0.3;              // flume width
  double column_diameter = 0.018;  // seed 004 fig. 11: 18 mm wooden columns
  double horizontal_gap = 0.05;    // clear gap between vertical columns (l_H)
  double vertical_gap = 0.0;       // clear gap between horizontal beams (l_V); 0: no beams
  double height = 0.15;
};
// Vertical columns (and horizontal beams if vertical_gap > 0) as fixed cylinders, placed
// symmetrically across the flume with the given clear gaps (walls count as columns).
std::vector<int> add_grid_dam(DemWorld& world, const GridDamSpec& spec, const Material& material);

struct PackingSpec {
  Eigen::Vector3d box_min = Eigen::Vector3d::Zero();
  Eigen::Vector3d box_max = Eigen::Vector3d::Ones();
  std::vector<double> sphere_diameters;  // one entry per sphere
  int log_count = 0;
  double log_diameter = 0.01;  // seed 004: 10 x 100 mm logs
  double log_length = 0.1;
  unsigned seed = 1;
  int attempts_per_element = 2000;
};
struct Packing {
  std::vector<int> spheres;
  std::vector<int> logs;
  [[nodiscard]] std::vector<int> all() const;
};
// Rejection placement (seed 004 section 4.1(2)): random non-overlapping positions in the box,
// logs first with random horizontal axes. Throws std::runtime_error if an element cannot be
// placed.
Packing random_packing(DemWorld& world, const PackingSpec& spec, const Material& sphere_material,
                       const Material& log_material);

// Lets the packing fall under gravity for duration seconds (the drop method of seed 004;
// no fluid). Returns the largest speed at the end.
double settle(DemWorld& world, double duration);

// Seed 004 eq. (55): volume fraction of the debris elements still upstream of x_dam.
double capture_rate(const DemWorld& world, const std::vector<int>& debris, double x_dam);

// The debris flow's streamwise shape (seed 004 section 4.2(1), fig. 13: its length along the
// flume, about 1.1 m measured and 1.0 m computed about 1 m upstream of the dam; a head that
// rises a little; logs gathered at the front). Positions are bed coordinates (x along the bed,
// z normal to it). Quantiles are by volume, so a few elements thrown ahead or left behind do
// not set the length.
struct DebrisFront {
  double front = 0.0;   // x of the 99 % volume quantile [m]
  double tail = 0.0;    // x of the 1 % volume quantile [m]
  double length = 0.0;  // front - tail [m]
  double extent = 0.0;  // largest minus smallest centre x of all elements [m]
  // From the tail to the front in bins `bin` wide: the top of the debris (largest z + radius of
  // the elements whose centre is in the bin; 0 for an empty bin) [m] and the solid volume per
  // bed area (volume / (bin width)) [m].
  std::vector<double> bin_x, top, solid_depth;
  // The highest top within the front fifth of the length over the median top of the bins
  // behind it: above 1 the head stands higher than the body (a surge front).
  double head_over_body = 0.0;
  // Share of the log volume in the front third of [tail, front], over that third's share of
  // the whole debris volume: above 1 the logs gather at the front. NaN without logs.
  double log_front_enrichment = 0.0;
};
DebrisFront debris_front(const DemWorld& world, const std::vector<int>& debris, double width,
                         double bin = 0.05);

// Prescribed flow for the flume frame after seed 004 eq. (50): velocity U at the surface, 0.8 U
// on the bed, water fraction 1 below depth h and 0 above; one entry per moving element.
void prescribed_flume_flow(const DemWorld& world, const Eigen::Vector3d& surface_velocity,
                           double depth, std::vector<Eigen::Vector3d>& velocity,
                           std::vector<double>& water_fraction);

// Seed 004 eq. (51)-(53), the flow just upstream of the dam while debris is being trapped:
// a trapezoidal profile over the ponded depth h_dam that carries the same discharge as eq. (50)
// over the approach depth h. Returns the factor on U at height z (0 above h_dam).
double capture_flow_factor(double z, double depth, double dam_depth);

}  // namespace cosim::dem
