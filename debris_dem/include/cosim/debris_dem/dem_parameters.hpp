// Parameters of the 3D DEM (seed 004): element materials, the fluid force model and the
// numerics, each scenario key declared once (visit_parameters, cosim/scenario/parameters.hpp)
// for the scenario parser, the library's check and `cosim keys`.
#pragma once

#include <Eigen/Core>
#include <concepts>
#include <cstdint>
#include <limits>
#include <type_traits>

#include "cosim/debris_dem/contact_law.hpp"
#include "cosim/scenario/parameters.hpp"

namespace cosim::dem {

// Contact spring parameters are per element material; a pair uses the mean of its two
// materials (identical materials give exactly the table 3 values of seed 004).
struct Material {
  double density = 1900.0;              // kg/m^3 (seed 004 table 3: spheres 1.9, logs 0.8)
  double normal_stiffness = 1.0e4;      // K_n, N/m (seed 004 table 3)
  double tangential_stiffness = 4.0e3;  // K_s, N/m (seed 004 table 3)
  // Damping ratio h of the normal and tangential dashpots (seed 004 table 3: h = 0.2). If
  // restitution > 0 it overrides: the damping ratio that gives this head-on e under the normal
  // law in use (damping_ratio_for_restitution in contact_law.hpp), so e is what is asked whether
  // or not the normal force is clipped.
  double damping_ratio = 0.2;
  double restitution = 0.0;
  double friction = 0.404;  // tan(phi) of the Mohr-Coulomb limit, cohesion c = 0 (table 3)

  // clipped: DemParameters::clip_normal_force of the world the material is used in.
  [[nodiscard]] double effective_damping_ratio(bool clipped) const;
};

// Drag on an element in the fluid (dem_fluid.cpp).
enum class DragLaw : std::uint8_t {
  // Seed 004 eq. (48): constant C_D (drag_coefficient_sphere / _cylinder) on the projected area.
  kSeed004,
  // Spheres: Schiller & Naumann (1933) C_D(Re), Re on the diameter. Logs: the crossflow
  // (independence) principle, Hoerner, Fluid-Dynamic Drag (1965): the velocity component
  // normal to the axis drives C_D(Re_n) of a circular cylinder (White's fit) on D L, the axial
  // component the sphere C_D(Re_t) of the log's diameter on the end area pi r^2 (end-on flow
  // past a blunt body; logs in a stream mostly see crossflow).
  kSchillerNaumann,
};

struct DemParameters {
  // Gravity in the world frame; slope_gravity() in scenes.hpp tilts it for a flume frame.
  Eigen::Vector3d gravity{0.0, 0.0, -9.81};
  double fluid_density = 1000.0;
  double drag_coefficient_sphere = 0.49;  // seed 004 section 4.1(3), from Hashimoto et al.
  // Seed 004 gives a log the drag of a sphere of equal projected area; here the area normal to
  // the relative flow, 2 r L sin + pi r^2 cos, is used with this coefficient.
  double drag_coefficient_cylinder = 0.49;
  // The unresolved CFD-DEM force set (Zhou, Kuang, Chu & Yu, J. Fluid Mech. 661 (2010) 482-510):
  // drag, pressure gradient and added mass, all on the submerged volume V_sub. The defaults
  // keep seed 004's drag and buoyancy alone.
  DragLaw drag_law = DragLaw::kSeed004;
  double fluid_viscosity = 1.0e-3;  // mu, Pa s (water at 20 C), for the Reynolds numbers
  // Multiply the drag by eps^(2 - chi) of Di Felice (1994), eps the local fluid volume fraction
  // local_voidage() estimates from the moving elements within voidage_radius (m, several
  // element diameters), updated once per window (elements move far less than the radius in
  // one). Needs kSchillerNaumann.
  bool voidage_correction = false;
  double voidage_radius = 0.0;
  // Pressure-gradient force -V_sub grad p with grad p = rho_f (g - Du/Dt): besides buoyancy
  // -rho_f V_sub g it adds rho_f V_sub Du/Dt (the fluid's acceleration at the element).
  bool fluid_acceleration_force = false;
  // Added mass rho_f V_sub C (Du/Dt - dv/dt), integrated implicitly (the element's inertia
  // becomes m + rho_f V_sub C), so light elements stay stable. C = C_a for spheres (0.5, potential
  // flow: Lamb, Hydrodynamics, 6th ed. (1932)); for logs the tensor C_n (I - a a^T) + C_t a a^T:
  // C_n = 1 of a circular cylinder per unit length and C_t ~ 0 along a slender body (Newman,
  // Marine Hydrodynamics (1977) ch. 4; Brennen, A review of added mass and fluid inertial forces,
  // NCEL CR 82.010 (1982)). The contact dashpots keep the solid mass (pair_constants).
  bool added_mass = false;
  double added_mass_sphere = 0.5;
  double added_mass_cylinder_normal = 1.0;
  double added_mass_cylinder_axial = 0.0;
  double list_margin = 5.0e-3;  // r_dam of table 3: extra reach of candidate lists
  // t_reset of table 3 (s): seed 004 rebuilds its lists every 1e-3 s. Infinity (the default):
  // no fixed interval, the list is rebuilt only when two elements may have closed the margin
  // (list_sweep_guard), the half-skin rule of a Verlet list (Allen & Tildesley, Computer
  // Simulation of Liquids (1987) 5.3). Results do not depend on it while the guard is on (a list
  // that holds every pair within the margin gives the same forces in the same order); in the
  // settling benchmark it cuts rebuilds from 40 to about 10 per 4000 steps.
  double list_reset_interval = std::numeric_limits<double>::infinity();
  // Also rebuild the list as soon as two elements may have closed the margin (translation plus a
  // log's end sweep); false keeps only the fixed interval of the seed.
  bool list_sweep_guard = true;
  // OpenMP threads for contacts, integration and lists. 1 by default: in a co-simulation the
  // solvers already share the cores, and an oversubscribed barrier costs more than it saves.
  int threads = 1;
  double safety_factor = 0.1;      // dt = safety_factor * sqrt(m_min / k_max)
  double user_dt = 0.0;            // > 0 forces this sub-step (seed 004: 1e-5 s)
  double max_overlap_ratio = 0.5;  // overlap / smaller radius that stops the run
  double region_size = 1.0;        // local-origin cell size, section 2.4(10) (m)
  // true: total normal force (spring + dashpot) is clipped at zero, no tension (seed 004
  // fig. 3a). false: the dashpot may pull while overlapping, matching the closed form of e.
  bool clip_normal_force = true;
  Eigen::Vector3d domain_min = Eigen::Vector3d::Constant(-1.0e6);
  Eigen::Vector3d domain_max = Eigen::Vector3d::Constant(1.0e6);
};

inline constexpr scenario::Choices<DragLaw, 2> kDragLaws{
    {{"seed004", DragLaw::kSeed004}, {"schiller_naumann", DragLaw::kSchillerNaumann}}};

// The keys of `participants.debris_dem` that are DemParameters, declared once for the parser,
// validate_parameters() and `cosim keys` (cosim/scenario/parameters.hpp). Seed 004's drag law
// keeps its buoyancy-only defaults; Schiller-Naumann defaults to the full unresolved CFD-DEM set.
// Not keys: gravity (the scene's), the domain (from the structure), threads, region_size,
// clip_normal_force, list_sweep_guard.
template <class P, class V>
requires std::same_as<std::remove_const_t<P>, DemParameters>
void visit_parameters(P& p, V& v) {
  using scenario::Key;
  using scenario::Range;
  v(Key("drag_law").doc("seed004: constant C_D; schiller_naumann: C_D(Re)"), p.drag_law, kDragLaws);
  const bool seed = p.drag_law == DragLaw::kSeed004;
  v(Key("fluid_density").unit("kg/m^3").in(Range::non_negative()).doc("rho_f"), p.fluid_density);
  v(Key("drag_coefficient_sphere")
        .in(Range::non_negative())
        .only_with(seed, "drag_law: seed004")
        .doc("C_D of a sphere"),
    p.drag_coefficient_sphere);
  v(Key("drag_coefficient_cylinder")
        .in(Range::non_negative())
        .only_with(seed, "drag_law: seed004")
        .doc("C_D of a log on its area normal to the flow"),
    p.drag_coefficient_cylinder);
  // From superfluid helium to bitumen, so a unit slip (mPa s for Pa s) shows up.
  v(Key("fluid_viscosity")
        .unit("Pa s")
        .in(Range::between(1e-7, 1e6))
        .only_with(!seed, "drag_law: schiller_naumann")
        .doc("mu, for the Reynolds numbers"),
    p.fluid_viscosity);
  v(Key("voidage_correction").doc("Di Felice eps^(2 - chi) on the drag"), p.voidage_correction);
  v.rule("voidage_correction", !(p.voidage_correction && seed), "needs drag_law: schiller_naumann");
  v(Key("voidage_radius")
        .unit("m")
        .in(Range::positive())
        .needed()
        .only_with(p.voidage_correction, "voidage_correction: true")
        .doc("reach of the local voidage, several diameters"),
    p.voidage_radius);
  const char* full_set = "false with seed004, true with schiller_naumann";
  v(Key("fluid_acceleration_force")
        .scenario_default(seed ? 0.0 : 1.0, full_set)
        .doc("rho_f V Du/Dt besides buoyancy"),
    p.fluid_acceleration_force);
  v(Key("added_mass").scenario_default(seed ? 0.0 : 1.0, full_set).doc("implicit added mass"),
    p.added_mass);
  // 0 (none) up to 5, beyond any rigid body's in unbounded fluid (a flat plate broadside aside).
  const Range coefficient = Range::between(0.0, 5.0);
  const char* with_added_mass = "added_mass: true";
  v(Key("added_mass_coefficient")
        .in(coefficient)
        .only_with(p.added_mass, with_added_mass)
        .doc("C_a of a sphere"),
    p.added_mass_sphere);
  v(Key("added_mass_coefficient_log_normal")
        .in(coefficient)
        .only_with(p.added_mass, with_added_mass)
        .doc("C_n of a log, across its axis"),
    p.added_mass_cylinder_normal);
  v(Key("added_mass_coefficient_log_axial")
        .in(coefficient)
        .only_with(p.added_mass, with_added_mass)
        .doc("C_t of a log, along its axis"),
    p.added_mass_cylinder_axial);
  v(Key("substep")
        .unit("s")
        .in(Range::non_negative())
        .scenario_default(1.0e-5)
        .doc("DEM sub-step (seed 004: 1e-5 s); 0: safety_factor sqrt(m_min / k_max)"),
    p.user_dt);
  v(Key("safety_factor").in(Range{0.0, 1.0, true}).doc("of the stable step, when substep is 0"),
    p.safety_factor);
  v(Key("list_margin")
        .unit("m")
        .in(Range::non_negative())
        .doc("r_dam: extra reach of the lists (0: rebuilt every sub-step)"),
    p.list_margin);
  v(Key("list_reset_interval")
        .unit("s")
        .in(Range::non_negative())
        .omitted_means("none: rebuilt on displacement only")
        .doc("t_reset: fixed rebuild interval (0: every sub-step)"),
    p.list_reset_interval);
  v(Key("max_overlap_ratio").in(Range{0.0, 1.0, true}).doc("overlap / smaller radius that stops"),
    p.max_overlap_ratio);
}

// Scenario defaults of the three materials: debris and structure as seed 004 table 3 (s.g.
// 1.9), logs of s.g. 0.8.
inline Material default_debris_material() {
  return Material{};
}
inline Material default_log_material() {
  Material m;
  m.density = 800.0;
  return m;
}

// The keys of `materials.debris`, `materials.logs` and `materials.structure`.
template <class P, class V>
requires std::same_as<std::remove_const_t<P>, Material>
void visit_parameters(P& m, V& v) {
  using scenario::Key;
  using scenario::Range;
  v(Key("density").unit("kg/m^3").in(Range::positive()).doc("element density"), m.density);
  v(Key("normal_stiffness").unit("N/m").in(Range::positive()).doc("K_n"), m.normal_stiffness);
  v(Key("tangential_stiffness").unit("N/m").in(Range::non_negative()).doc("K_s"),
    m.tangential_stiffness);
  v(Key("damping_ratio").in(Range::between(0.0, 1.0)).doc("h of both dashpots"), m.damping_ratio);
  v(Key("restitution").in(Range::between(0.0, 1.0)).doc("head-on e; > 0 overrides damping_ratio"),
    m.restitution);
  v(Key("friction").in(Range::non_negative()).doc("tan(phi) of Mohr-Coulomb"), m.friction);
}

// The library's checks: the declared ranges and rules, and a restitution some damping ratio
// reaches (the bisection of damping_ratio_for_restitution ends at zeta = 1e8, e ~ 1e-17).
// Throw scenario::ParameterError naming the key.
void validate_parameters(const DemParameters& p);
void validate_material(const Material& m);

// Rough memory per element [bytes]: the 64-byte aligned Element, the per-moving arrays (forces,
// fluid terms, hot copies) and the candidate pairs measured 1.06 kB per sphere of a touching
// lattice in the library (RSS after a window); the process's link and output buffers add some.
inline constexpr double kBytesPerElement = 1500.0;

}  // namespace cosim::dem
