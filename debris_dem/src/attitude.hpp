// Attitude of a log over one DEM step (dem_step.cpp's integration): the exact turn of a free
// symmetric top.
#pragma once

#include <Eigen/Geometry>

namespace cosim::dem {

// The attitude q of an axisymmetric body (principal moments inertia = (I_t, I_t, I_a), body z
// its axis, world axis `axis` = q e_z) turned over dt with its angular momentum (world) held.
Eigen::Quaterniond free_top_turn(const Eigen::Quaterniond& q, const Eigen::Vector3d& momentum,
                                 const Eigen::Vector3d& axis, const Eigen::Vector3d& inertia,
                                 double dt);

}  // namespace cosim::dem
