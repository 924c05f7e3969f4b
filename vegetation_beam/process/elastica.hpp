// Steady large deflection of a clamped plant in a uniform stream: the elastica with the drag of
// the normal velocity component (seed 000 eq. 16: |u_n| u_n) and net buoyancy as distributed
// loads, solved by shooting from the free tip. Independent of the node-chain model, it is the
// reference for the single-blade scene.
#pragma once

#include <vector>

namespace cosim::vegetation {

struct ElasticaProblem {
  double length = 0;             // m
  double bending_stiffness = 0;  // EI, N m^2
  double width = 0;              // frontal width b, m
  double thickness = 0;          // m
  double plant_density = 0;      // kg/m^3
  double fluid_density = 1000;   // kg/m^3
  double drag_coefficient = 1;
  double speed = 0;    // stream speed, perpendicular to the unstressed plant, m/s
  double gravity = 0;  // m/s^2, acting against the unstressed plant's direction
  int steps = 4000;    // integration steps along the plant
};

// One sample of the bent shape, at arc length s from the base.
struct ElasticaPoint {
  double s = 0;           // m
  double angle = 0;       // rad from the unstressed direction, towards the stream
  double streamwise = 0;  // position along the stream relative to the base, m
  double height = 0;      // position along the unstressed direction relative to the base, m
};

struct ElasticaSolution {
  double tip_streamwise = 0;         // tip position along the stream relative to the base, m
  double tip_height = 0;             // tip position along the unstressed direction, m
  double tip_angle = 0;              // rad from the unstressed direction
  std::vector<ElasticaPoint> shape;  // steps + 1 samples, base (s = 0) first
};

// The physical equilibrium: the shape whose angle grows monotonically from the base to the tip.
// Above Cauchy numbers of about 100 the shooting problem has further clamped solutions whose
// angle swings back and forth along the plant (S-shapes, loops against the stream); they are
// skipped. Throws std::runtime_error if no monotone equilibrium has a tip angle in [0, pi/2).
ElasticaSolution solve_elastica(const ElasticaProblem& problem);

// True if the angle of `shape` never falls back by more than `tolerance` rad from base to tip.
bool is_monotone(const std::vector<ElasticaPoint>& shape, double tolerance = 1e-9);

}  // namespace cosim::vegetation
