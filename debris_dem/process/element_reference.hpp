// References of single-element scenes: a sphere settling in still liquid against the terminal
// velocity of a drag correlation (shared/references/settling_and_floating.md), and a floating body
// against its Archimedes draft, with the decay of its heave oscillation.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "cosim/coupler/metrics.hpp"
#include "cosim/scenario/parameters.hpp"

namespace cosim::dem {

// Terminal velocity [m/s] of a sphere of diameter d and density rho_s in a liquid (rho_f, mu)
// under gravity g: (rho_s - rho_f) g V = 0.5 rho_f C_D(Re) A v^2 with the Schiller-Naumann C_D,
// solved by bisection on v (the balance is monotone in v). Throws for a sphere that floats.
double schiller_naumann_terminal_velocity(double diameter, double solid_density,
                                          double fluid_density, double viscosity, double gravity);

// Draft of a horizontal cylinder of diameter D and density ratio s floating: the submerged
// circular segment has area fraction s, (theta - sin theta) / (2 pi) = s with draft
// D/2 (1 - cos(theta/2)) (settling_and_floating.md: 0.746 D for s = 0.8).
double floating_cylinder_draft(double diameter, double density_ratio);
// Draft of a floating sphere: the spherical cap of volume fraction s.
double floating_sphere_draft(double diameter, double density_ratio);

enum class ReferenceKind { settling, floating, hindered };
inline constexpr scenario::Choices<ReferenceKind, 3> kElementReferenceKinds{
    {{"settling", ReferenceKind::settling},
     {"floating", ReferenceKind::floating},
     {"hindered", ReferenceKind::hindered}}};

struct ElementReferenceSettings {
  ReferenceKind kind = ReferenceKind::settling;
  double average_from = 0.0;  // [s] time averages start here
};

// Follows one element through the run and reports against its reference.
class ElementReference {
 public:
  ElementReference(ElementReferenceSettings settings, double reference_value, double radius);
  // time [s], element centre (world), velocity, the free surface above it (-inf: none).
  void observe(double time, const Eigen::Vector3d& center, const Eigen::Vector3d& velocity,
               double surface);
  void report(coupler::MetricsReport& report) const;
  const std::vector<double>& times() const { return times_; }
  const std::vector<double>& heights() const { return heights_; }
  const std::vector<double>& vertical_velocities() const { return vertical_; }

 private:
  void report_settling(coupler::MetricsReport& report) const;
  void report_floating(coupler::MetricsReport& report) const;
  void report_heave(coupler::MetricsReport& report) const;

  ElementReferenceSettings settings_;
  double reference_;
  double radius_;
  std::vector<double> times_, heights_, vertical_, drafts_;
};

// Richardson & Zaki (1954) exponent n of v = v_t (1 - phi)^n, without wall correction
// (settling_and_floating.md): 4.65 below Re_t 0.2, 4.4 Re_t^-0.03 to 1, 4.4 Re_t^-0.1 to 500,
// 2.4 above.
double richardson_zaki_exponent(double terminal_reynolds);

// A suspension of equal spheres settling in a closed column: the volume-weighted mean settling
// velocity against Richardson & Zaki, v_t (1 - phi)^n with v_t the Schiller-Naumann terminal
// velocity of one sphere.
class SuspensionReference {
 public:
  // phi: the solids' volume over the volume of the suspension they start in.
  SuspensionReference(double average_from, double phi, double terminal_velocity,
                      double terminal_reynolds);
  void observe(double time, const Eigen::Vector3d& mean_velocity);
  void report(coupler::MetricsReport& report) const;

 private:
  double average_from_, phi_, terminal_velocity_, reynolds_;
  double sum_ = 0.0;
  int count_ = 0;
};

}  // namespace cosim::dem
