#include "keys_command.hpp"

#include <functional>
#include <map>
#include <utility>

#include "boundary_keys.hpp"
#include "cosim/debris_dem/dem_world.hpp"
#include "cosim/fluid_mps/parameters.hpp"
#include "cosim/prescribed_flow/profiles.hpp"
#include "cosim/scenario/parameters.hpp"
#include "cosim/scenario/scene.hpp"
#include "cosim/vegetation_beam/plant_field.hpp"
#include "reference_keys.hpp"
#include "scene_keys.hpp"
#include "section_keys.hpp"
#include "structure_keys.hpp"

namespace cosim::tool {

namespace {

using scenario::KeyTable;

struct Group {
  std::string title;   // where the keys sit in the participant's section
  std::string source;  // the header that declares them
  KeyTable table;
};

struct Participant {
  std::string name;
  std::string note;
  std::function<std::vector<Group>()> groups;
};

template <class T>
Group group(std::string title, std::string source, std::string prefix, const T& defaults = T{}) {
  Group g{std::move(title), std::move(source), KeyTable(std::move(prefix))};
  scenario::describe_parameters(g.table, defaults);
  return g;
}

// More rows under another prefix in the same table.
template <class T>
void add_rows(Group& g, std::string prefix, const T& defaults = T{}) {
  g.table.set_prefix(std::move(prefix));
  scenario::describe_parameters(g.table, defaults);
}

std::vector<Group> vegetation_groups() {
  const char* header = "vegetation_beam/include/cosim/vegetation_beam/plant_field.hpp";
  const char* section_keys = "vegetation_beam/process/section_keys.hpp";
  std::vector<Group> groups{
      group<vegetation::BeamParameters>("BeamParameters", header, ""),
      group<vegetation::PlantSpec>("PlantSpec, one per `plants` entry", header, "plants[].",
                                   vegetation::scenario_plant_defaults()),
      group<vegetation::PlantRow>("A `plants` entry as a row of equal plants", section_keys,
                                  "plants[]."),
      group<vegetation::CanopySettings>("Canopy measures (seed 000 section 4)", section_keys,
                                        "canopy.")};
  Group checks = group<vegetation::PointLoadSettings>(
      "Beam checks (references/cantilever.md): loads and plucks per `plants` entry, a static "
      "start and modes for the section",
      section_keys, "plants[].point_loads[].");
  add_rows<vegetation::PluckSettings>(checks, "plants[].pluck.");
  add_rows<vegetation::BeamChecks>(checks, "");
  groups.push_back(std::move(checks));
  groups.push_back(
      group<vegetation::ElasticaReference>("The reference", section_keys, "reference."));
  return groups;
}

std::vector<Group> debris_groups() {
  const char* header = "debris_dem/include/cosim/debris_dem/dem_parameters.hpp";
  const char* structure = "debris_dem/process/structure_keys.hpp";
  std::vector<Group> groups{
      group<dem::DemParameters>("DemParameters", header, ""),
      group<dem::Material>("Material of spheres", header, "materials.debris.",
                           dem::default_debris_material()),
      group<dem::Material>("Material of logs", header, "materials.logs.",
                           dem::default_log_material()),
      group<dem::Material>("Material of the structure", header, "materials.structure.",
                           dem::default_debris_material())};
  Group flume = group<dem::FlumeSpec>(
      "The structure: seed 004's flume (bed_roughness and dam need it) and a box", structure,
      "flume.");
  add_rows<dem::RoughnessSettings>(flume, "bed_roughness.");
  add_rows<dem::GridDamSpec>(flume, "dam.");
  add_rows<dem::BoxSettings>(flume, "box.");
  groups.push_back(std::move(flume));
  Group packing = group<dem::PackingSpec>(
      "The random packing (seed 004 section 4.1(2)) and its gate", structure, "packing.");
  add_rows<dem::SphereClass>(packing, "packing.spheres[].");
  add_rows<dem::GateSettings>(packing, "gate.");
  groups.push_back(std::move(packing));
  groups.push_back(
      group<dem::ElementSettings>("Elements, one per `elements` entry", structure, "elements[]."));
  groups.push_back(group<dem::ElementReferenceSettings>("The reference", structure, "reference."));
  return groups;
}

std::vector<Group> fluid_groups() {
  const char* scene_keys = "fluid_mps/process/scene_keys.hpp";
  const char* boundary_keys = "fluid_mps/process/boundary_keys.hpp";
  const char* reference_keys = "fluid_mps/process/reference_keys.hpp";
  mps::FluidConfig config_defaults;
  mps::SceneSettings scene_defaults;
  mps::ReferenceSettings reference_defaults;
  mps::ObservationSettings observation_defaults;
  std::vector<Group> groups{
      group<mps::MpsParameters>("MpsParameters", "fluid_mps/include/cosim/fluid_mps/parameters.hpp",
                                ""),
      group("The section's own keys", scene_keys, "", mps::FluidSectionKeys{config_defaults}),
      group("The scene: its kind and walls", scene_keys, "scene.", mps::SceneKeys{scene_defaults})};
  // One group per kind, so a kind added to kSceneKinds is listed with its keys.
  for (const auto& kind : mps::kSceneKinds) {
    mps::visit_scene_kind(kind.value, scene_defaults, [&](const auto& keys) {
      groups.push_back(
          group(fmt::format("The scene with kind: {}", kind.name), scene_keys, "scene.", keys));
    });
  }
  groups.push_back(group<mps::OpenBoundarySettings>(
      fmt::format("The inflow, a soluble moving wall (kind: {}; required there)",
                  mps::scene_kinds_where(mps::has_inflow)),
      boundary_keys, "scene.inflow."));
  groups.push_back(group<mps::ChainStateSettings>(
      "The start of a periodic_pool from one pool of a pool_fishway run's frame (kind: "
      "periodic_pool; absent or null: the pool starts level)",
      boundary_keys, "scene.chain_state."));
  Group solids = group<mps::ObstacleKeys>(
      "Solids in a 3D tank (dimension: 3): `scene.obstacles` boxes and `scene.solids` STL "
      "surfaces, one per entry",
      boundary_keys, "scene.obstacles[].");
  add_rows<mps::StlSolidKeys>(solids, "scene.solids[].");
  groups.push_back(std::move(solids));
  groups.push_back(group<mps::RestartSettings>(
      "A restart from an output frame (the scene still describes the tank)", boundary_keys,
      "restart."));
  groups.push_back(group<mps::PartitionSegment>("Thin partitions, one per `partitions` entry",
                                                boundary_keys, "partitions[]."));
  groups.push_back(group("Observation points", reference_keys, "observe.",
                         mps::ObserveKeys{observation_defaults, {}}));
  groups.push_back(
      group("The reference", reference_keys, "reference.", mps::ReferenceKeys{reference_defaults}));
  for (const auto& kind : mps::kReferenceKinds) {
    mps::visit_reference_kind(kind.value, reference_defaults, [&](const auto& keys) {
      groups.push_back(group(fmt::format("The reference with kind: {}", kind.name), reference_keys,
                             "reference.", keys));
    });
  }
  Group sensors = group<mps::PressureProbeKeys>(
      "Sensors of kind: probe_series, one per `reference.pressure_probes` or "
      "`reference.depth_gauges` entry",
      reference_keys, "reference.pressure_probes[].");
  add_rows<mps::DepthGaugeKeys>(sensors, "reference.depth_gauges[].");
  groups.push_back(std::move(sensors));
  return groups;
}

const std::vector<Participant>& participants() {
  static const std::vector<Participant> list{
      {"fluid_mps",
       "A key of another scene or reference kind is refused as \"only used with kind: ...\". "
       "The checks that need another section or a file (a reference's scene, a restart's "
       "frames, whole cells of a 3D tank, the STL surfaces and measured records) are in "
       "`fluid_mps/process/fluid_config.cpp` and `scene_3d.cpp`.",
       fluid_groups},
      {"vegetation_beam",
       "`output_interval` is read in `vegetation_beam/process/vegetation_config.cpp`.",
       vegetation_groups},
      {"debris_dem",
       "`walls` (STL files, `scenario/include/cosim/scenario/stl_section.hpp`), `front_gauge_x` "
       "and `output_interval` are read in `debris_dem/process/dem_config.cpp`.",
       debris_groups},
      {"prescribed_flow", "",
       [] {
         return std::vector<Group>{group<prescribed_flow::ProfileSettings>(
             "ProfileSettings",
             "stand_ins/prescribed_flow/include/cosim/prescribed_flow/profiles.hpp", "")};
       }},
      {"top level",
       "These keys sit at the top of `scenario.yaml`, not under `participants`; `name`, "
       "`duration`, `output_interval`, `coupling` and `world` are read in "
       "`scenario/src/scene.cpp`.",
       [] {
         return std::vector<Group>{
             group<scenario::RunSettings>("RunSettings",
                                          "scenario/include/cosim/scenario/scene.hpp", ""),
             group<scenario::InterfaceSettings>(
                 "InterfaceSettings", "scenario/include/cosim/scenario/scene.hpp", "coupling."),
             group<scenario::ImplicitSettings>(
                 "ImplicitSettings (read with coupling.scheme serial-implicit or "
                 "parallel-implicit)",
                 "scenario/include/cosim/scenario/scene.hpp", "coupling.implicit.")};
       }},
  };
  return list;
}

// A table cell: code for keys, '|' escaped.
std::string cell(const std::string& text) {
  std::string out;
  for (char c : text) out += c == '|' ? std::string("\\|") : std::string(1, c);
  return out;
}

std::string participant_markdown(const Participant& participant) {
  std::string out = fmt::format("## {}\n\n", participant.name);
  for (const Group& g : participant.groups()) {
    out += fmt::format("{} (`{}`):\n\n", g.title, g.source);
    out += "| key | type | default | range | unit | description |\n";
    out += "|---|---|---|---|---|---|\n";
    for (const auto& row : g.table.rows()) {
      out += fmt::format("| `{}` | {} | {} | {} | {} | {} |\n", row.key, row.type,
                         cell(row.default_value), cell(row.range), cell(row.unit),
                         cell(row.description));
    }
    out += "\n";
    if (!g.table.rules().empty()) {
      out += "Rules:\n\n";
      for (const auto& rule : g.table.rules()) out += "- " + rule + "\n";
      out += "\n";
    }
  }
  if (!participant.note.empty()) out += participant.note + "\n\n";
  return out;
}

}  // namespace

std::vector<std::string> keyed_participants() {
  std::vector<std::string> names;
  for (const auto& p : participants()) names.push_back(p.name);
  return names;
}

std::string keys_markdown(const std::string& name) {
  std::string out;
  if (name.empty()) {
    out +=
        "# Scenario keys\n\n"
        "Generated by `cosim keys` from the parameter declarations (`visit_parameters` beside "
        "each parameter struct, `scenario/include/cosim/scenario/parameters.hpp`); do not edit: "
        "`tests/tools/keys_test.cpp` checks this file equals the command's output. Each key sits "
        "under `participants.<name>` of a `scenario.yaml`. The same declaration is what "
        "`cosim validate` reads and what each library checks its struct against, so a value "
        "refused at process start is refused by `validate` with its file and line.\n\n"
        "Ranges: `[` and `]` include the bound, `(` and `)` exclude it. A default `required` "
        "means the scenario must give the key; \"only with\" keys are refused otherwise.\n\n";
  }
  for (const auto& participant : participants()) {
    if (name.empty() || participant.name == name) out += participant_markdown(participant);
  }
  while (out.size() >= 2 && out.ends_with("\n\n")) out.pop_back();
  return out;
}

}  // namespace cosim::tool
