// The top level of a scenario bundle: which participants run, how they are coupled, for how
// long, and where outputs go. Each participant's own section is checked by that participant's
// parser, registered by the caller, so every error is found before any process starts.
#pragma once

#include <Eigen/Core>
#include <filesystem>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "cosim/scenario/parameters.hpp"
#include "cosim/scenario/section.hpp"

namespace cosim::scenario {

enum class Role { flow, solid };

// Implicit coupling (coupling.scheme serial-implicit or parallel-implicit): each window is
// iterated, every participant rolled back to its window start, until the fields the solids hand
// the flow (and in the parallel scheme the flow's velocity samples) no longer change. Keys under
// `coupling.implicit`.
enum class Acceleration { none, constant, aitken, iqn_ils };
inline constexpr Choices<Acceleration, 4> kAccelerations{{{"none", Acceleration::none},
                                                          {"constant", Acceleration::constant},
                                                          {"aitken", Acceleration::aitken},
                                                          {"iqn-ils", Acceleration::iqn_ils}}};
enum class AtMaxIterations { continue_run, stop };
inline constexpr Choices<AtMaxIterations, 2> kAtMaxIterations{
    {{"continue", AtMaxIterations::continue_run}, {"stop", AtMaxIterations::stop}}};

struct ImplicitSettings {
  int max_iterations = 30;
  double relative_tolerance = 1e-4;
  double absolute_force = 1e-9;     // [N]
  double absolute_position = 1e-9;  // [m]
  double absolute_velocity = 1e-8;  // [m/s]
  AtMaxIterations at_max_iterations = AtMaxIterations::continue_run;
  Acceleration acceleration = Acceleration::iqn_ils;
  double relaxation = 0.5;
  int reuse_windows = 0;
  double filter = 1e-10;
  double max_step = 0;  // 0: unbounded
  bool positive_aitken = false;
};

template <class P, class V>
requires std::same_as<std::remove_const_t<P>, ImplicitSettings>
void visit_parameters(P& p, V& v) {
  v(Key("max_iterations")
        .in(Range::between(1, 1000))
        .doc("most coupling iterations of one window (1: the explicit scheme's result)"),
    p.max_iterations);
  v(Key("relative_tolerance")
        .in(Range::non_negative())
        .doc("converged when |H(x) - x| <= this * |H(x)| for each exchanged field (2-norm)"),
    p.relative_tolerance);
  v(Key("absolute_force")
        .unit("N")
        .in(Range::non_negative())
        .doc("or when the root-mean-square change of a force field is below this"),
    p.absolute_force);
  v(Key("absolute_position").unit("m").in(Range::non_negative()).doc("the same for positions"),
    p.absolute_position);
  v(Key("absolute_velocity").unit("m/s").in(Range::non_negative()).doc("the same for velocities"),
    p.absolute_velocity);
  v(Key("at_max_iterations")
        .doc("a window not converged in max_iterations: continue (a warning, counted in "
             "summary.json) or stop the run naming the window"),
    p.at_max_iterations, kAtMaxIterations);
  v(Key("acceleration")
        .doc("next input from the iterates: none (plain iteration), constant under-relaxation, "
             "aitken, iqn-ils (quasi-Newton inverse least squares)"),
    p.acceleration, kAccelerations);
  v(Key("relaxation")
        .in(Range{0.0, 1.0, true})
        .doc("constant: the factor; aitken: the first factor of a window; iqn-ils: the first "
             "step of a window without columns"),
    p.relaxation);
  v(Key("reuse_windows")
        .in(Range::between(0, 100))
        .doc("iqn-ils: windows whose columns are kept for the next windows"),
    p.reuse_windows);
  v(Key("max_step")
        .in(Range::non_negative())
        .doc("aitken, iqn-ils: an update x_next - x longer than this times the residual |H(x) - x| "
             "(in the scaled fields) is shortened to it, along its direction (0: unbounded)"),
    p.max_step);
  v(Key("positive_aitken")
        .doc("aitken: a factor that comes out zero or negative starts again from relaxation "
             "(maps with no eigenvalue above 1, as the added mass of a light structure gives)"),
    p.positive_aitken);
  v(Key("filter")
        .in(Range::between(0.0, 1.0))
        .doc("iqn-ils: drop a column whose part orthogonal to newer ones is below this times its "
             "length (QR2 filter)"),
    p.filter);
}

// What crosses the plants' interface (keys directly under `coupling`). By default a plant feels
// the flow through its own Morison drag and added mass on the relative velocity (the flow's
// velocity samples) and the flow takes minus that drag. With resolved_plants the 2D fluid stands
// each plant in the flow as a moving line of wall particles at its nodes: the fluid's pressure on
// them is the plants' only fluid load (their drag and added mass are off), so the water's inertia
// reaches the plants through the exchange, as in a partitioned fluid-structure solver with a
// resolved interface (Causin, Gerbeau & Nobile 2005, CMAME 194; Hwang et al. 2014, J. Fluids
// Struct.).
struct InterfaceSettings {
  bool resolved_plants = false;
};

template <class P, class V>
requires std::same_as<std::remove_const_t<P>, InterfaceSettings>
void visit_parameters(P& p, V& v) {
  v(Key("resolved_plants")
        .doc("fluid_mps (2D) represents the vegetation_beam plant as a moving line of wall "
             "particles at its nodes and sends its pressure force per node as the plant's fluid "
             "load; the plant's drag and added mass are off (one plant, serial or "
             "parallel-explicit or serial-implicit)"),
    p.resolved_plants);
}

struct CouplingSettings {
  // serial-explicit, parallel-explicit, serial-implicit, parallel-implicit
  std::string scheme = "serial-explicit";
  ImplicitSettings implicit;
  InterfaceSettings interface;
  bool is_implicit() const { return scheme.ends_with("-implicit"); }
  bool is_serial() const { return scheme.starts_with("serial-"); }
  double window = 1e-3;           // fixed window length [s]
  bool adaptive_window = false;   // window = min(window, flow's stable dt)
  double timeout = 5.0;           // seconds of silence before a participant is hung
  double resend_interval = 0.05;  // seconds between retransmissions
  int chunk_values = 4096;        // float64 values per message chunk
};

// The one world frame every participant works in (docs/architecture.md): right-handed, x along
// the flow (along the bed of a sloping flume), y across it, z up (normal to the bed). A 2D flow
// lives in the x-z plane and stands for a slice of `span` width along y. Gravity is declared once
// for the scene; a sloping bed tilts it in the x-z plane: g (sin theta, 0, -cos theta).
struct WorldSettings {
  Eigen::Vector3d gravity{0.0, 0.0, -9.81};  // [m/s^2]
  double slope_degrees = 0.0;                // bed slope theta the gravity was tilted by
};

// Gravity of magnitude g tilted by a bed slope of theta degrees (flow down the slope along +x).
Eigen::Vector3d slope_gravity(double slope_degrees, double g = 9.81);

struct ParticipantEntry {
  std::string name;        // key in the scenario ("fluid_mps", "replay", ...)
  std::string executable;  // process to start
  std::string acts_as;     // the name it publishes under (replay acts as the recorded one)
  Role role = Role::solid;
};

// Run-level keys at the top of scenario.yaml, declared like the participants' parameters (so
// `cosim keys` lists them).
struct RunSettings {
  double checkpoint_interval = 0.0;  // [s] of simulated time; 0: checkpoints on SIGINT/SIGTERM only
};

template <class P, class V>
requires std::same_as<std::remove_const_t<P>, RunSettings>
void visit_parameters(P& p, V& v) {
  v(Key("checkpoint_interval")
        .unit("s")
        .in(Range::non_negative())
        .doc("simulated time between coupled checkpoints (checkpoints/ of the run folder; 0: "
             "only when interrupted by SIGINT/SIGTERM)"),
    p.checkpoint_interval);
}

// The most windows a scene may ask for: 1e9 windows is weeks of coupling at the fastest rates
// measured; more is a typo in duration or window (a bigger count used to wrap round).
inline constexpr double kMaxWindows = 1.0e9;

struct Scene {
  std::filesystem::path file;  // scenario.yaml
  std::string name;
  std::string description;
  double duration = 0.0;
  double output_interval = 0.0;
  RunSettings run;
  CouplingSettings coupling;
  WorldSettings world;
  std::vector<ParticipantEntry> participants;  // flow provider first, then solids
  YAML::Node resolved;                         // every value used, defaults included

  // Windows of the nominal length that cover `duration` (parse checks it is 1 to kMaxWindows).
  int64_t total_windows() const;
  const ParticipantEntry* flow() const;
  std::vector<const ParticipantEntry*> solids() const;
  const ParticipantEntry& participant(const std::string& acts_as) const;
};

// Checks one participant's section (throws ScenarioError naming file, line, key). The scene's
// top level (duration, coupling, output_interval) is already read when it is called.
struct Scene;
using ParticipantParser = std::function<void(Section& section, const Scene& scene)>;

// Every participant a scene may name, with its role ("replay" takes its replayed one's role).
const std::map<std::string, Role>& participant_roles();

// Loads <bundle>/scenario.yaml (or the file itself), checks the top level and every participant
// section with `parsers` (one per name of participant_roles()), and returns the scene with its
// resolved YAML. Unknown keys anywhere are errors.
Scene load_scene(const std::filesystem::path& bundle_or_file,
                 const std::map<std::string, ParticipantParser>& parsers);

// The same for a document already in memory (e.g. with command-line overrides applied); `file`
// names it in messages and resolves relative file names.
Scene load_scene(const YAML::Node& document, const std::filesystem::path& file,
                 const std::map<std::string, ParticipantParser>& parsers);

// Sets `dotted.key.path` of a scenario document to a YAML value given as text ("0.004",
// "[1, 0, 0]", "true"), creating missing mappings.
void apply_override(YAML::Node& document, const std::string& dotted_key, const std::string& value);

// Reads a resolved scenario written by a run, which was checked when the run started; the
// participant sections are left to each process's own parser.
Scene load_resolved_scene(const std::filesystem::path& file);

std::string role_name(Role role);

}  // namespace cosim::scenario
