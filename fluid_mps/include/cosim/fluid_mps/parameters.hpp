// Parameters, particle kinds and errors of the 2D/3D MPS fluid solver.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <concepts>
#include <stdexcept>
#include <string>
#include <vector>

#include "cosim/fluid_mps/kernels.hpp"
#include "cosim/scenario/parameters.hpp"

namespace cosim::mps {

// Periodic boundary in x (streamwise), seed 001 section 2.2(4) and seed 000 section 3.1: a
// particle leaving x_max re-enters at x_min and every operator (neighbour search, number density,
// gradient, Laplacian, Poisson matrix, collision) uses the minimum-image distance across the seam
// (equivalent to seed 001's ghost copies of fig. 2.4 (1), without copying). The constant pressure
// difference of seed 000 section 3.1 is applied as the equivalent body force: fluid particles get
// the acceleration driving_pressure_drop / (rho (x_max - x_min)) along +x.
// The period must exceed three times the largest influence radius.
// With a `drop` the copy one period downstream also lies `drop` lower (a chain of stepped pools,
// seed 001 Run-OC): a particle leaving at x_max re-enters at x_min raised by `drop`, and the
// neighbours across the seam are seen with that offset.
struct PeriodicBoundary {
  bool enabled = false;
  double x_min = 0.0;
  double x_max = 0.0;
  double driving_pressure_drop = 0.0;  // [Pa] over one period, p(x_min) - p(x_max)
  double drop = 0.0;                   // [m] fall of y per period along +x
  double length() const { return x_max - x_min; }
  // Minimum-image displacement; identity when disabled.
  Eigen::Vector3d wrap(Eigen::Vector3d d) const {
    if (enabled) {
      const double l = length();
      if (d.x() > 0.5 * l) {  // the upstream copy: higher by drop
        d.x() -= l;
        d.y() += drop;
      }
      if (d.x() < -0.5 * l) {  // the downstream copy: lower by drop
        d.x() += l;
        d.y() -= drop;
      }
    }
    return d;
  }
  // x folded into [x_min, x_max); identity when disabled.
  double fold(double x) const {
    if (!enabled) return x;
    const double l = length();
    double y = x - l * std::floor((x - x_min) / l);
    if (y >= x_max) y -= l;  // rounding
    return y;
  }
  // A position moved into the period, y raised by `drop` per period moved upstream.
  Eigen::Vector3d fold(Eigen::Vector3d position) const {
    if (!enabled) return position;
    const double folded = fold(position.x());
    position.y() += drop * std::round((position.x() - folded) / length());
    position.x() = folded;
    return position;
  }
};

// Thin partition wall of seed 001 section 2.2(1): two particles whose connecting segment crosses
// a partition segment are not neighbours in any operator (x-y plane; z is ignored). Place the
// segment along the middle of the partition's wall particles. With keep_walls (default), as in
// seed 001, only fluid-fluid pairs are cut: the partition's wall and dummy particles are seen
// from both sides, so a partition two particles thick still supports the water on each side.
struct PartitionSegment {
  Eigen::Vector2d a = Eigen::Vector2d::Zero();
  Eigen::Vector2d b = Eigen::Vector2d::Zero();
  bool keep_walls = true;
};

// Physical and numerical parameters. Equation numbers refer to seed 001 (Maeno et al.) unless
// marked "seed 000" (Ikari & Gotoh).
struct MpsParameters {
  int dimension = 2;               // D0 of seed 001 eqs. (3), (4), (8), (9)
  double particle_spacing = 0.01;  // l0 [m]
  double density = 1000.0;         // rho [kg/m^3]
  double kinematic_viscosity = 1e-6;
  Eigen::Vector3d gravity{0.0, -9.81, 0.0};
  // Influence radii r_e = l_r l0 per operator (seed 001 eq. (6)). Seed 001 quotes 2.1 / 2.1 / 4.0
  // as the usual recommendation and found a gradient radius of 8.0 l0 best for its fishway.
  double radius_density_over_l0 = 2.1;
  double radius_gradient_over_l0 = 2.1;
  double radius_laplacian_over_l0 = 4.0;
  double surface_threshold = 0.97;  // beta: free surface where n* < beta n0
  // Collision model, seed 001 eqs. (10)-(11): d_c = d_cr l0, V_c = V_r (1 + C_c).
  // Seed 001 settles on d_cr = 1.0, C_c = -0.8 for the fishway; 0.5 / 0.2 is its milder run PF-1.
  double collision_distance_ratio = 0.5;
  double collision_restitution = 0.2;
  // Fluid-wall pairs collide within wall_collision_factor d_c (1: as fluid pairs). With d_cr = 1.0,
  // the wall lattice's own spacing, the rows next to a wall rest on its particles' tops in
  // permanent collision and ride over them like a rough bed (docs/validation.md, free_overfall).
  double wall_collision_factor = 1.0;
  double courant = 0.2;
  double diffusion_number = 0.2;  // viscous limit dt <= diffusion_number l0^2 / nu
  double max_dt = 1e-3;           // user upper bound [s]
  double pcg_tolerance = 1e-8;    // relative residual |b - A p| / |b|
  int pcg_max_iterations = 2000;
  // Preconditioner of the pressure conjugate gradients (pressure_solver.hpp): aggregation and
  // amg keep the iterations about constant as the resolution grows (22-30 and 12-13 per step
  // from a/l0 = 10 to 80 on the dam break, against 30-200 with jacobi); aggregation's set-up is
  // the cheaper. automatic takes jacobi for small systems and aggregation above (1 000 unknowns
  // in 2D, 10 000 in 3D; pressure_solver.hpp).
  enum class PressurePreconditioner { amg, jacobi, incomplete_cholesky, automatic, aggregation };
  PressurePreconditioner pressure_preconditioner = PressurePreconditioner::automatic;
  // aggregation: how many solves one set-up (aggregates and coarse factor) may serve; it is
  // rebuilt sooner once the CG takes 2 iterations more than on its first solve
  // (pressure_solver.hpp). 1: a new set-up every step.
  int pressure_setup_reuse = 10;
  // The products of the CG iterations read the matrix values rounded to float: 6 instead of 10
  // bytes an entry, for a product bound by reading the matrix. Changes the bits of the pressure
  // (a matrix perturbed by at most 2^-24 relative an entry); off by default
  // (docs/performance.md: its cost and its effect on the validation figures). It pays where a
  // thread's share of the matrix outgrows its cache in double but not in float: honami_field
  // (17 k unknowns, 48 entries a row) sets it, for a pressure solve 0.91 as long.
  bool single_precision_product = false;
  // What the CG products read (pressure_solver.hpp): upper_triangle reads each pair of the
  // symmetric matrix once (half the bytes; the result still does not depend on the thread
  // count, but it is another order of the same additions, so other bits than full_rows). It
  // pays where the product is bound by reading the matrix: the 3D step at 38 k particles took
  // 0.82 of full_rows' time on one thread and 0.97 on two; a 2D step (14 k unknowns) 0.9 on one
  // thread but 1.10 on two (docs/performance.md). automatic: upper_triangle in 3D, full_rows in
  // 2D (a choice from the scene alone, so runs and restarts stay bit-identical). With full_rows
  // the unknowns are numbered along space (spatial_order.hpp), with upper_triangle by particle id.
  enum class PressureProduct { automatic, full_rows, upper_triangle };
  PressureProduct pressure_product = PressureProduct::automatic;
  // amg: radius [l0] of the Laplacian model the multigrid hierarchy is built from (capped at the
  // Laplacian radius). Shorter than radius_laplacian_over_l0 makes the set-up and the cycles
  // cheaper for a few more iterations; 2.5 was the fastest of 2.1 / 2.5 / 3.0 / 4.0 measured at
  // a/l0 = 80 (13 iterations per step against 15, 11 and 6; docs/performance.md).
  double multigrid_radius_over_l0 = 2.5;
  // Ikeda-type artificial compressibility [1/Pa]: keeps the Poisson matrix strictly positive
  // definite when a cluster of particles has no free-surface neighbour.
  double compressibility = 0.45e-9;
  // Source term of the pressure Poisson equation.
  //  density: -gamma rho/dt^2 (n* - n0)/n0 (seed 001 / Koshizuka-Oka; gamma = 1 is the original
  //           scheme, the Koshizuka textbook code uses 0.2);
  //  mixed:   rho/dt div(u*) - gamma rho/dt^2 (n^k - n0)/n0 (Tanaka & Masunaga 2010), which
  //           removes the velocity divergence fully and the density error gently (gamma ~ 0.01
  //           to 0.05): much quieter pressure in still water.
  enum class SourceTerm { density, mixed };
  SourceTerm source_term = SourceTerm::density;
  double pressure_relaxation = 0.2;  // gamma
  // Pressure gradient model.
  //  minimum:   d/n0 sum (p_j - p^_i) r_ij w / r^2 with p^_i the smallest pressure around i
  //             (Koshizuka-Oka; seed 000 eq. (2) with p^_i for stability). Pair forces are not
  //             equal and opposite, so the fluid's own pressure creates net momentum.
  //  symmetric: d/n0 sum (p_i + p_j) r_ij w / r^2 (the pair form of SPH): antisymmetric in i, j,
  //             so fluid-fluid pressure forces conserve linear momentum exactly and stay
  //             repulsive (p >= 0). Exact for a linear p on a full lattice, but the p_i sum
  //             pulls particles towards lattice sites: still water is noisier and fluid next to
  //             a wall locks onto the wall lattice (a bed friction far above the viscous one).
  //             Subtracting each particle's p^ as well (CMPS of Khayyer & Gotoh 2008) keeps the
  //             symmetry but leaves only the gradient of p - p^, about zero in hydrostatic water.
  //  symmetric_normal_wall: the symmetric form; of the walls' share, the part 2 p_i sum r w/r^2
  //             (absolute pressure times the wall lattice's bumps) is pressed onto the local wall
  //             normal (a smooth wall, as polygon walls: Harada et al. 2008, Mitsume et al. 2015),
  //             the part (p_w - p_i) kept whole: the wall lattice cannot lock the fluid.
  //  corrected: the minimum form times the correction matrix C_i = [sum w r_ij r_ij^T/r^2]^-1
  //             (Khayyer & Gotoh 2011; first-order LSMPS, Tamai & Koshizuka 2014): exact for a
  //             linear pressure on any arrangement, not momentum-conserving.
  //  corrected_interior: the correction matrix only where particle i and every fluid neighbour
  //             within the gradient radius are off the free surface (a full neighbourhood), the
  //             minimum form elsewhere: near the surface the missing neighbours shrink the
  //             moment matrix and C_i amplifies the one-sided p^_i part (what put the corrected
  //             still water 17 % low and its dam-break front 14 % ahead).
  //  corrected_blended: the minimum form times (1 - w_i) I + w_i n0/d C_i, the weight w_i a
  //             smoothstep of how full i's neighbourhood is (n_i / n0 at the gradient radius, from
  //             0 at the surface threshold beta to 1 at n0): the correction matrix in the
  //             interior, the minimum form on the surface, no switch in between (renormalised
  //             gradients blended with the plain one: Oger et al. 2007; Khayyer & Gotoh 2011).
  //  corrected_split: the minimum form split as sum (p_j - p_i) F + (p_i - p^_i) sum F (F_ij =
  //             r_ij w / r^2): the blended matrix of corrected_blended on the first part (the
  //             Taylor difference, which the correction makes exact for a linear p), the second
  //             (the repulsion p^_i adds) uncorrected, so the inverse cannot amplify it where
  //             the neighbourhood is one-sided.
  // pressure_gradient.hpp has the operators; docs/validation.md (rigid_canopy) what each gave.
  enum class GradientForm {
    minimum,
    symmetric,
    symmetric_normal_wall,
    corrected,
    corrected_interior,
    corrected_blended,
    corrected_split
  };
  GradientForm gradient_form = GradientForm::minimum;
  // What the gradient operator carries (hydrostatic_background.hpp):
  //  none:        the whole pressure p.
  //  hydrostatic: q = p - p_b, with p_b = rho |g| (eta - h) of the local water column (faded in
  //               over the gradient radius below the surface) added back by its exact gradient,
  //               so the operator's error scales with q, not with the hydrostatic pressure;
  //               weighed by the trust S against the operator on p where the column is not
  //               hydrostatic (steep surfaces, steps in the bed, water no wall holds up).
  enum class PressureBackground { none, hydrostatic };
  PressureBackground pressure_background = PressureBackground::none;
  // With pressure_background: hydrostatic, the repulsion (x_i - x^_i) sum F of the forms with a
  // neighbourhood minimum (add_full_pressure_repulsion in pressure_gradient.hpp):
  //  dynamic: q's own (the form run on q alone); near zero in water at rest, so a lattice
  //           kicked by its first settling is not held (a 3D still tank keeps stirring);
  //  full:    the whole pressure's, of order rho g r_e, as without the background, faded in
  //           with the background below the surface; the Taylor part of the form stays on q
  //           (docs/validation.md, rigid_canopy, eighth round).
  enum class BackgroundRepulsion { dynamic, full };
  BackgroundRepulsion background_repulsion = BackgroundRepulsion::dynamic;
  // How the background fades in over the depth delta below the surface, where the operator
  // still carries the surface particles' weight (hydrostatic_background.hpp):
  //  taper: p_b = rho g f(d), f = d^2 / (2 delta) above delta; the operator sees q = p - p_b,
  //         which is curved in that layer;
  //  blend: p_b = rho g d stays linear and the trust S of the background's estimate is scaled
  //         by min(d / delta, 1), so the layer steps with the operator on p at the surface and
  //         with the background's below; every field the operator sees stays linear in still
  //         water (docs/validation.md, rigid_canopy, ninth round).
  enum class BackgroundFade { taper, blend };
  BackgroundFade background_fade = BackgroundFade::taper;
  // delta over the gradient radius r_e.
  double background_fade_depth_over_re = 1.0;
  // What the background's exact gradient replaces of the operator's Taylor part on p_b
  // (keep_layer_deviation in pressure_gradient.hpp):
  //  particle:   each particle's own (the operator sees q alone; a resting lattice loses the
  //              stiffness that sum's dependence on the arrangement gives);
  //  layer_mean: only its mean over the particles at the same depth (layers l0 / 2 thick), the
  //              operator's bias; each particle keeps its deviation from it, the default's
  //              stiffness (docs/validation.md, rigid_canopy, ninth round).
  enum class BackgroundReplaces { particle, layer_mean };
  BackgroundReplaces background_replaces = BackgroundReplaces::particle;
  // Particle shifting (Lind et al. 2012): dr = -A l0 |u| dt grad C away from crowded places,
  // velocities unchanged (momentum kept); A = 0 switches it off. Lind et al. use A of 1-6.
  double shifting_coefficient = 0.0;
  // The velocity a shifted particle carries (shift_particles):
  //  kept:   its own (the fluid's momentum is untouched);
  //  taylor: u_i + (dr . grad) u_i, the flow's velocity where it now sits (Lind et al. 2012,
  //          eq. 13; grad u by the corrected MPS gradient), first order, not momentum-conserving.
  enum class ShiftedVelocity { kept, taylor };
  ShiftedVelocity shifted_velocity = ShiftedVelocity::kept;
  // Shifting beside walls (shift_particles):
  //  full:       along the whole concentration gradient, walls' particles included;
  //  tangential: the shift's component along the walls' share of grad C is removed, so a
  //              particle slides along a wall but is never pushed off it (away from the crowded
  //              first row above a bed into faster water, which with taylor is a momentum source
  //              no force gave: rigid_canopy's balance 6.4 % with full, 1.0 % with tangential).
  enum class ShiftingNearWalls { full, tangential };
  ShiftingNearWalls shifting_near_walls = ShiftingNearWalls::full;
  double runaway_speed = 50.0;  // [m/s]; faster particles stop the run with a StabilityError
  // Lattice of the initial particles of the 3D scene builders (scenes.hpp), on which n0 and
  // lambda are computed (kernels.hpp, lattice_sums).
  //  cubic: simple cubic of spacing l0 (seed 001), every particle l0^3.
  //  fcc:   face-centred cubic with the same volume l0^3 per particle (cube edge 4^(1/3) l0,
  //         4 particles per cube, 12 nearest neighbours at 2^(1/6) l0 = 1.12 l0): the close
  //         packing that is stable under isotropic pressure, where the simple cubic lattice is
  //         a saddle for repulsive pair forces (Born 1940; Ashcroft & Mermin ch. 4). 3D only.
  enum class FillLattice { cubic, fcc };
  FillLattice fill_lattice = FillLattice::cubic;
  // Set by the 3D scene builders, not a key: how much the fcc fill's layer spacing along x, y, z
  // is stretched (by at most 1/(2n) for n layers) for whole layers to fit the water; n0, lambda
  // and the particle mass (rho times the volume per particle) are taken on that lattice.
  Eigen::Vector3d fill_stretch = Eigen::Vector3d::Ones();
  // Particles outside are 'escaped'. Empty box: the bounding box of the initial particles grown
  // by 20 l0 on each side.
  Eigen::AlignedBox3d domain;
  // Open and periodic boundaries (boundaries.hpp): see PeriodicBoundary and PartitionSegment.
  PeriodicBoundary periodic;
  std::vector<PartitionSegment> partitions;
};

inline constexpr scenario::Choices<MpsParameters::PressurePreconditioner, 5> kPreconditioners{
    {{"automatic", MpsParameters::PressurePreconditioner::automatic},
     {"amg", MpsParameters::PressurePreconditioner::amg},
     {"jacobi", MpsParameters::PressurePreconditioner::jacobi},
     {"incomplete_cholesky", MpsParameters::PressurePreconditioner::incomplete_cholesky},
     {"aggregation", MpsParameters::PressurePreconditioner::aggregation}}};
inline constexpr scenario::Choices<MpsParameters::PressureProduct, 3> kPressureProducts{
    {{"automatic", MpsParameters::PressureProduct::automatic},
     {"full_rows", MpsParameters::PressureProduct::full_rows},
     {"upper_triangle", MpsParameters::PressureProduct::upper_triangle}}};
inline constexpr scenario::Choices<MpsParameters::SourceTerm, 2> kSourceTerms{
    {{"mixed", MpsParameters::SourceTerm::mixed}, {"density", MpsParameters::SourceTerm::density}}};
inline constexpr scenario::Choices<MpsParameters::PressureBackground, 2> kPressureBackgrounds{
    {{"none", MpsParameters::PressureBackground::none},
     {"hydrostatic", MpsParameters::PressureBackground::hydrostatic}}};
inline constexpr scenario::Choices<MpsParameters::BackgroundRepulsion, 2> kBackgroundRepulsions{
    {{"dynamic", MpsParameters::BackgroundRepulsion::dynamic},
     {"full", MpsParameters::BackgroundRepulsion::full}}};
inline constexpr scenario::Choices<MpsParameters::BackgroundFade, 2> kBackgroundFades{
    {{"taper", MpsParameters::BackgroundFade::taper},
     {"blend", MpsParameters::BackgroundFade::blend}}};
inline constexpr scenario::Choices<MpsParameters::BackgroundReplaces, 2> kBackgroundReplaces{
    {{"particle", MpsParameters::BackgroundReplaces::particle},
     {"layer_mean", MpsParameters::BackgroundReplaces::layer_mean}}};
inline constexpr scenario::Choices<MpsParameters::GradientForm, 7> kGradientForms{
    {{"minimum", MpsParameters::GradientForm::minimum},
     {"symmetric", MpsParameters::GradientForm::symmetric},
     {"symmetric_normal_wall", MpsParameters::GradientForm::symmetric_normal_wall},
     {"corrected", MpsParameters::GradientForm::corrected},
     {"corrected_interior", MpsParameters::GradientForm::corrected_interior},
     {"corrected_blended", MpsParameters::GradientForm::corrected_blended},
     {"corrected_split", MpsParameters::GradientForm::corrected_split}}};
inline constexpr scenario::Choices<MpsParameters::ShiftedVelocity, 2> kShiftedVelocities{
    {{"kept", MpsParameters::ShiftedVelocity::kept},
     {"taylor", MpsParameters::ShiftedVelocity::taylor}}};
inline constexpr scenario::Choices<MpsParameters::ShiftingNearWalls, 2> kShiftingNearWalls{
    {{"full", MpsParameters::ShiftingNearWalls::full},
     {"tangential", MpsParameters::ShiftingNearWalls::tangential}}};
inline constexpr scenario::Choices<MpsParameters::FillLattice, 2> kFillLattices{
    {{"cubic", MpsParameters::FillLattice::cubic}, {"fcc", MpsParameters::FillLattice::fcc}}};

// The keys of `participants.fluid_mps` that are MpsParameters, each declared once
// (cosim/scenario/parameters.hpp): the scenario parser, validate_parameters() and `cosim keys`
// all visit this list. Gravity, the domain, periodic seams and partitions come from the scene.
template <class P, class V>
requires std::same_as<std::remove_const_t<P>, MpsParameters>
void visit_parameters(P& p, V& v) {
  using scenario::Key;
  using scenario::Range;
  const Range radius{1.0, 10.0, true};  // [l0]: beyond 10 l0 the neighbour lists explode
  v(Key("dimension").in(Range::between(2, 3)).doc("2: the world's x-z plane, 3: full 3D"),
    p.dimension);
  v(Key("particle_spacing").unit("m").in(Range::positive()).needed().doc("l0"), p.particle_spacing);
  v(Key("density").unit("kg/m^3").in(Range::positive()).doc("rho"), p.density);
  v(Key("kinematic_viscosity").unit("m^2/s").in(Range::non_negative()).doc("nu"),
    p.kinematic_viscosity);
  v(Key("radius_density_over_l0").in(radius).doc("number-density influence radius / l0"),
    p.radius_density_over_l0);
  v(Key("radius_gradient_over_l0").in(radius).doc("gradient influence radius / l0"),
    p.radius_gradient_over_l0);
  v(Key("radius_laplacian_over_l0").in(radius).doc("Laplacian influence radius / l0"),
    p.radius_laplacian_over_l0);
  v(Key("surface_threshold")
        .in(Range::below(0.5, 1.0))
        .doc("beta: free surface where n* < beta n0 (1 would make every particle a surface)"),
    p.surface_threshold);
  v(Key("collision_distance_ratio").in(Range::between(0.0, 1.5)).doc("d_cr: d_c = d_cr l0"),
    p.collision_distance_ratio);
  v(Key("collision_restitution").in(Range::between(-1.0, 1.0)).doc("C_c of the collision model"),
    p.collision_restitution);
  v(Key("wall_collision_factor")
        .in(Range::between(0.0, 1.5))
        .doc("fluid-wall pairs collide within this times d_c (1: as fluid pairs)"),
    p.wall_collision_factor);
  v(Key("courant").in(Range{0.0, 1.0, true}).doc("Courant number of the step limit"), p.courant);
  v(Key("diffusion_number").in(Range{0.0, 0.5, true}).doc("viscous limit dt <= D l0^2 / nu"),
    p.diffusion_number);
  v(Key("max_dt").unit("s").in(Range::positive()).doc("upper bound of the step"), p.max_dt);
  v(Key("pcg_tolerance").in(Range{0.0, 1e-2, true}).doc("relative residual of the pressure CG"),
    p.pcg_tolerance);
  v(Key("pcg_max_iterations").in(Range::between(1, 1e7)).doc("pressure CG iterations per step"),
    p.pcg_max_iterations);
  v(Key("pressure_preconditioner")
        .doc("automatic: jacobi for small, aggregation for large systems"),
    p.pressure_preconditioner, kPreconditioners);
  v(Key("pressure_setup_reuse")
        .in(Range::between(1, 1000))
        .doc("aggregation: solves one set-up may serve (1: a new one every step)"),
    p.pressure_setup_reuse);
  v(Key("single_precision_product").doc("CG products read float matrix values (changes the bits)"),
    p.single_precision_product);
  v(Key("pressure_product")
        .doc("CG products: automatic (3D: upper_triangle), full_rows, upper_triangle"),
    p.pressure_product, kPressureProducts);
  v(Key("multigrid_radius_over_l0").in(radius).doc("radius of the amg hierarchy's Laplacian / l0"),
    p.multigrid_radius_over_l0);
  v(Key("compressibility").unit("1/Pa").in(Range::non_negative()).doc("artificial compressibility"),
    p.compressibility);
  v(Key("source_term").doc("pressure Poisson source: density (seed 001) or mixed"), p.source_term,
    kSourceTerms);
  v(Key("pressure_relaxation").in(Range{0.0, 1.0, true}).doc("gamma of the source term"),
    p.pressure_relaxation);
  v(Key("runaway_speed").unit("m/s").in(Range::positive()).doc("faster particles stop the run"),
    p.runaway_speed);
  v(Key("pressure_gradient")
        .doc("minimum (Koshizuka-Oka), symmetric (momentum-conserving), symmetric_normal_wall "
             "(symmetric, smooth straight walls), corrected (correction matrix), "
             "corrected_interior (correction matrix off the free surface only), "
             "corrected_blended (correction matrix blended by how full the neighbourhood is) or "
             "corrected_split (the blend on the Taylor part only, p^_i's repulsion uncorrected)"),
    p.gradient_form, kGradientForms);
  v(Key("pressure_background")
        .doc("none, or hydrostatic: the gradient operator carries p - rho g (eta - h) of the "
             "local water column, whose exact gradient is added back"),
    p.pressure_background, kPressureBackgrounds);
  v(Key("background_repulsion")
        .only_with(p.pressure_background == MpsParameters::PressureBackground::hydrostatic &&
                       p.gradient_form != MpsParameters::GradientForm::symmetric &&
                       p.gradient_form != MpsParameters::GradientForm::symmetric_normal_wall,
                   "pressure_background: hydrostatic and a pressure_gradient with a neighbourhood "
                   "minimum (not the symmetric forms)")
        .doc("with pressure_background: hydrostatic, the neighbourhood-minimum repulsion "
             "(p_i - p^_i) sum F taken from q = p - p_b (dynamic) or from the whole pressure "
             "(full, faded in with the background: the stiffness that lets a resting lattice "
             "settle)"),
    p.background_repulsion, kBackgroundRepulsions);
  v(Key("background_fade")
        .only_with(p.pressure_background == MpsParameters::PressureBackground::hydrostatic,
                   "pressure_background: hydrostatic")
        .doc("how the background fades in below the surface: taper (p_b = rho g d^2 / (2 delta) "
             "above delta) or blend (p_b linear, the background's estimate weighed by "
             "min(d / delta, 1) against the operator on p)"),
    p.background_fade, kBackgroundFades);
  v(Key("background_fade_depth_over_re")
        .in(Range{0.0, 4.0, true})
        .only_with(p.pressure_background == MpsParameters::PressureBackground::hydrostatic,
                   "pressure_background: hydrostatic")
        .doc("delta, the depth of the background's fade-in, over the gradient radius"),
    p.background_fade_depth_over_re);
  v(Key("background_replaces")
        .only_with(p.pressure_background == MpsParameters::PressureBackground::hydrostatic,
                   "pressure_background: hydrostatic")
        .doc("what the background's exact gradient replaces of the operator's part on p_b: each "
             "particle's own (particle) or only its mean over each depth layer (layer_mean: the "
             "particles keep their deviation from it, the lattice's stiffness)"),
    p.background_replaces, kBackgroundReplaces);
  v(Key("shifting_coefficient")
        .in(Range::between(0.0, 10.0))
        .doc("A of particle shifting dr = -A l0 |u| dt grad C (Lind et al. 2012); 0: off"),
    p.shifting_coefficient);
  v(Key("shifted_velocity")
        .doc("kept (a shifted particle keeps its velocity; momentum conserved) or taylor (it "
             "takes u + (dr . grad) u at its new place, Lind et al. 2012)"),
    p.shifted_velocity, kShiftedVelocities);
  v(Key("shifting_near_walls")
        .doc("full (shift along the whole concentration gradient) or tangential (the component "
             "along the walls' share of it removed: particles slide along walls, never off them)"),
    p.shifting_near_walls, kShiftingNearWalls);
  v(Key("fill_lattice")
        .doc("3D start lattice: cubic (spacing l0) or fcc (face-centred cubic, l0^3 per "
             "particle, nearest neighbours 1.12 l0); n0 and lambda are taken on it"),
    p.fill_lattice, kFillLattices);
}

// Rough memory per particle [bytes]: about 25 per-particle vectors and scalars of FluidSystem
// (~600 B), and per neighbour within the largest radius about 40 B (the pair lists of the
// operators, the Poisson matrix row, the preconditioner's copy): 2D at 4 l0 ~2.6 kB, 3D ~11 kB.
inline double estimated_bytes_per_particle(const MpsParameters& p) {
  const double r =
      std::max({p.radius_density_over_l0, p.radius_gradient_over_l0, p.radius_laplacian_over_l0});
  const double neighbours = p.dimension == 3 ? 4.18879 * r * r * r : 3.14159 * r * r;
  return 600.0 + 40.0 * neighbours;
}

// The library's check of MpsParameters: the declared ranges, then the periodic seam (set by the
// scene builders). Throws scenario::ParameterError ("MpsParameters: key 'k': problem").
void validate_parameters(const MpsParameters& p);

// n0, lambda and the neighbour count of the start lattice (fill_lattice, fill_stretch) at the
// radius radius_over_l0 l0, and the volume per particle of that lattice [m^3 in 3D, m^2 in 2D].
LatticeSums fill_lattice_sums(const MpsParameters& p, double radius_over_l0);
double fill_volume_per_particle(const MpsParameters& p);

// The largest reach of any operator [m]: influence radii and the collision distance.
inline double largest_influence_radius(const MpsParameters& p) {
  return std::max({p.radius_density_over_l0, p.radius_gradient_over_l0, p.radius_laplacian_over_l0,
                   p.collision_distance_ratio,
                   p.collision_distance_ratio * p.wall_collision_factor}) *
         p.particle_spacing;
}

// Seed 001's tuned set for its fishway (Run-PF-6): d_cr = 1.0, C_c = -0.8 and a gradient radius
// of 8.0 l0. Walls then need at least 8 layers of pressure-carrying particles.
inline MpsParameters seed001_fishway_parameters(double particle_spacing) {
  MpsParameters p;
  p.particle_spacing = particle_spacing;
  p.collision_distance_ratio = 1.0;
  p.collision_restitution = -0.8;
  p.radius_gradient_over_l0 = 8.0;
  return p;
}

// inactive: a recycled particle kept in the pool of the open boundaries (seed 001 section 2.2(3)):
// it takes part in no operator, is never checked for escape and keeps its slot so that the arrays
// stay fixed-size.
enum class ParticleKind { fluid, wall, dummy, inactive };

inline bool is_fluid(ParticleKind kind) {
  return kind == ParticleKind::fluid;
}
inline bool is_inactive(ParticleKind kind) {
  return kind == ParticleKind::inactive;
}
// Fluid and wall particles carry a pressure (an unknown of the Poisson equation or a free-surface
// zero); dummies and inactive particles do not.
inline bool carries_pressure(ParticleKind kind) {
  return kind == ParticleKind::fluid || kind == ParticleKind::wall;
}

// Initial particles of a scene. Wall and dummy particles move with their (prescribed) velocity.
struct ParticleSet {
  std::vector<Eigen::Vector3d> positions;
  std::vector<ParticleKind> kinds;
  std::vector<Eigen::Vector3d> velocities;
  std::size_t size() const { return positions.size(); }
  void add(const Eigen::Vector3d& position, ParticleKind kind,
           const Eigen::Vector3d& velocity = Eigen::Vector3d::Zero()) {
    positions.push_back(position);
    kinds.push_back(kind);
    velocities.push_back(velocity);
  }
};

// NaN, escaped particle or runaway velocity. The message names the step, particle and quantity.
class StabilityError : public std::runtime_error {
 public:
  StabilityError(long step, long particle, const std::string& quantity, const std::string& detail)
      : std::runtime_error("fluid_mps unstable at step " + std::to_string(step) + ", particle " +
                           std::to_string(particle) + ", " + quantity + ": " + detail),
        step_(step),
        particle_(particle),
        quantity_(quantity) {}
  long step() const { return step_; }
  long particle() const { return particle_; }
  const std::string& quantity() const { return quantity_; }

 private:
  long step_;
  long particle_;
  std::string quantity_;
};

}  // namespace cosim::mps
