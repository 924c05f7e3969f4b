// Steady large deflection of a clamped plant in a uniform stream: the elastica with the drag of
// the normal velocity component (seed 000 eq. 16: |u_n| u_n) and net buoyancy as distributed
// loads, solved by shooting from the free tip. Independent of the node-chain model, it is the
// reference for the single-blade scene.
#pragma once

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

struct ElasticaSolution {
  double tip_streamwise = 0;  // tip displacement along the stream, m
  double tip_height = 0;      // tip position along the unstressed direction, m
  double tip_angle = 0;       // rad from the unstressed direction
};

// Throws std::runtime_error if no equilibrium is found in [0, pi/2).
ElasticaSolution solve_elastica(const ElasticaProblem& problem);

}  // namespace cosim::vegetation
