// The debris_dem scenario section: the existing flume scenes keep their meaning, box and
// explicit-element scenes with the full fluid force set parse, and every error names file, line
// and key.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <numbers>
#include <optional>
#include <sstream>
#include <tuple>

#include "cosim/debris_dem/scenes.hpp"
#include "cosim/prescribed_flow/config.hpp"
#include "cosim/scenario/scene.hpp"
#include "dem_config.hpp"

namespace cosim::dem {
namespace {

std::map<std::string, scenario::ParticipantParser> parsers(std::optional<DebrisConfig>& out) {
  return {
      {"debris_dem", [&out](scenario::Section& section,
                            const scenario::Scene& scene) { out = parse_config(section, scene); }},
      {"prescribed_flow", [](scenario::Section& section, const scenario::Scene&) {
         prescribed_flow::parse_settings(section);
       }}};
}

std::filesystem::path write_scene(const std::string& body) {
  const auto folder = std::filesystem::temp_directory_path() / "cosim-dem-config-test";
  std::filesystem::create_directories(folder);
  std::ofstream(folder / "scenario.yaml")
      << "name: t\nduration: 0.1\ncoupling:\n  window: 0.01\nparticipants:\n  debris_dem:\n"
      << body;
  return folder / "scenario.yaml";
}

DebrisConfig parse_body(const std::string& body) {
  std::optional<DebrisConfig> config;
  scenario::load_scene(write_scene(body), parsers(config));
  return *config;
}

TEST(DemConfig, ExistingFlumeScenesKeepTheSeed004Model) {
  for (const char* scene : {"debris_capture_small", "debris_capture"}) {
    std::optional<DebrisConfig> config;
    scenario::load_scene(std::filesystem::path(COSIM_SCENARIOS) / scene, parsers(config));
    ASSERT_TRUE(config.has_value()) << scene;
    const DemParameters& p = config->parameters;
    EXPECT_EQ(p.drag_law, DragLaw::kSeed004) << scene;
    EXPECT_FALSE(p.added_mass);
    EXPECT_FALSE(p.fluid_acceleration_force);
    EXPECT_FALSE(p.voidage_correction);
    EXPECT_DOUBLE_EQ(p.drag_coefficient_sphere, 0.49);
    ASSERT_TRUE(config->flume && config->dam && config->packing && config->gate) << scene;
    EXPECT_FALSE(config->box);
    EXPECT_TRUE(config->elements.empty());
    // The domain of the flume scenes as before: far downstream and down, 1 m sideways.
    EXPECT_EQ(p.domain_min, Eigen::Vector3d(-1.0, -1.0, -100.0));
    EXPECT_EQ(p.domain_max.x(), config->flume->length + 100.0);
    // The flume's 15 degrees come from the scene's world: g (sin, 0, -cos).
    EXPECT_NEAR(p.gravity.x(), 9.81 * std::sin(15.0 * std::numbers::pi / 180.0), 1e-12);
    EXPECT_NEAR(p.gravity.z(), -9.81 * std::cos(15.0 * std::numbers::pi / 180.0), 1e-12);
  }
}

const char* kBoxScene = R"(    drag_law: schiller_naumann
    fluid_density: 970
    fluid_viscosity: 0.373
    voidage_correction: true
    voidage_radius: 0.05
    box: {min: [-0.05, -0.05, 0], max: [0.05, 0.05, 0.16]}
    elements:
      - {kind: sphere, center: [0, 0, 0.1275], diameter: 0.015, density: 1120}
      - {kind: log, center: [0, 0.02, 0.05], diameter: 0.01, length: 0.05, axis: [0, 2, 0],
         density: 800, velocity: [0.1, 0, 0]}
)";

TEST(DemConfig, BoxAndElementsWithTheUnresolvedFluidForceSet) {
  const DebrisConfig config = parse_body(kBoxScene);
  const DemParameters& p = config.parameters;
  EXPECT_EQ(p.drag_law, DragLaw::kSchillerNaumann);
  EXPECT_DOUBLE_EQ(p.fluid_viscosity, 0.373);
  EXPECT_TRUE(p.voidage_correction);
  EXPECT_DOUBLE_EQ(p.voidage_radius, 0.05);
  // The Schiller-Naumann law defaults to the whole set: pressure gradient and added mass.
  EXPECT_TRUE(p.fluid_acceleration_force);
  EXPECT_TRUE(p.added_mass);
  EXPECT_DOUBLE_EQ(p.added_mass_sphere, 0.5);
  EXPECT_DOUBLE_EQ(p.added_mass_cylinder_normal, 1.0);
  EXPECT_DOUBLE_EQ(p.added_mass_cylinder_axial, 0.0);
  EXPECT_FALSE(config.flume || config.packing || config.gate || config.dam);
  ASSERT_TRUE(config.box);
  ASSERT_EQ(config.elements.size(), 2u);
  EXPECT_FALSE(config.elements[0].is_log());
  EXPECT_DOUBLE_EQ(config.elements[0].material.density, 1120.0);
  EXPECT_TRUE(config.elements[1].is_log());
  EXPECT_EQ(config.elements[1].axis, Eigen::Vector3d::UnitY());
  EXPECT_EQ(config.elements[1].velocity, Eigen::Vector3d(0.1, 0, 0));
  // Element materials take the contact constants of materials.debris / materials.logs.
  EXPECT_DOUBLE_EQ(config.elements[1].material.friction, Material{}.friction);
  // Escape by more than 1 m sideways or below, 10 m above, is an error.
  EXPECT_EQ(p.domain_min, Eigen::Vector3d(-1.05, -1.05, -1.0));
  EXPECT_NEAR(p.domain_max.z(), 10.16, 1e-12);
}

// Message of the scenario error for `body`, with the line of the first line holding `needle`.
std::pair<std::string, int> error_and_line(const std::string& body, const std::string& needle) {
  const auto file = write_scene(body);
  std::ifstream in(file);
  std::string line;
  int line_number = 0, found = 0;
  while (std::getline(in, line)) {
    ++line_number;
    if (found == 0 && line.find(needle) != std::string::npos) found = line_number;
  }
  std::optional<DebrisConfig> config;
  try {
    scenario::load_scene(file, parsers(config));
  } catch (const scenario::ScenarioError& error) {
    return {error.what(), found};
  }
  return {"", found};
}

TEST(DemConfig, ErrorsNameFileLineAndKey) {
  const std::string sphere =
      "    elements:\n      - {kind: sphere, center: [0, 0, 0], "
      "diameter: 0.01, density: 1000}\n";
  struct Case {
    std::string body, needle, key, problem;
  };
  const std::vector<Case> cases{
      {"    voidage_correction: true\n" + sphere, "voidage_correction", "voidage_correction",
       "needs drag_law: schiller_naumann"},
      {"    drag_law: schiller_naumann\n    voidage_correction: true\n" + sphere, "drag_law",
       "voidage_radius", "required key is missing"},  // a missing key: its mapping
      {"    fluid_viscosity: 0.001\n" + sphere, "fluid_viscosity", "fluid_viscosity",
       "only used with drag_law: schiller_naumann"},
      {"    drag_law: schiller_naumann\n    added_mass_coefficient: 7\n" + sphere,
       "added_mass_coefficient", "added_mass_coefficient", "out of range"},
      {"    added_mass_coefficient: 0.5\n" + sphere, "added_mass_coefficient",
       "added_mass_coefficient", "only used with added_mass: true"},
      {"    drag_law: stokes\n" + sphere, "drag_law", "drag_law",
       "'stokes' is not one of: seed004, schiller_naumann"},
      {"    elements:\n      - {kind: sphere, center: [0, 0, 0], diameter: 0.01, length: 0.1,"
       " density: 1000}\n",
       "length", "elements[0].length", "only used with kind: log"},
      {"    elements:\n      - {kind: log, center: [0, 0, 0], diameter: 0.01, length: 0.1,\n"
       "         axis: [0, 0, 0], density: 800}\n",
       "axis", "elements[0].axis", "must not be the zero vector"},
      {"    elements:\n      - {kind: cube, center: [0, 0, 0], diameter: 0.01}\n", "cube",
       "elements[0].kind", "'cube' is not one of: sphere, log"},
      {"    box: {min: [0, 0, 0], max: [1, 0, 1]}\n" + sphere, "box", "box.max", "must exceed min"},
      {"    box: {min: [1, 1, 1], max: [2, 2, 2]}\n" + sphere, "kind: sphere", "elements[0].center",
       "lies outside the box"},
      {"    box: {min: [0, 0, 0], max: [1, 1, 1]}\n", "box", "elements",
       "nothing moves: give a packing or elements"},
      {"    dam: {x: 0.5, horizontal_gap: 0.05}\n" + sphere, "dam", "dam",
       "only used with a flume"},
      // Nested keys, read from their declarations (structure_keys.hpp).
      {"    flume: {length: 1.0, width: 0.3, wall_height: 0.15}\n"
       "    dam: {x: 0.5, horizontal_gap: 0.05, vertical_gap: -0.01}\n" +
           sphere,
       "vertical_gap", "dam.vertical_gap", "value -0.01 is out of range [0, inf]"},
      {"    flume: {length: 1.0, width: 0.3, wall_height: 0.15}\n"
       "    bed_roughness: {x0: 0.5, x1: 0.2, d_min: 0.007, d_max: 0.02}\n" +
           sphere,
       "bed_roughness", "bed_roughness.x1", "must exceed x0"},
      {"    packing:\n      box_min: [0, 0, 0]\n      box_max: [0.1, 0.1, 0.1]\n"
       "      seed: -3\n      spheres: [{diameter: 0.01, count: 5}]\n",
       "seed", "packing.seed", "value -3 is out of range [0, 2147483647]"},
      {"    packing:\n      box_min: [0, 0, 0]\n      box_max: [0.1, 0.1, 0.1]\n"
       "      spheres: [{diameter: 0.01}]\n",
       "spheres", "packing.spheres[0].count", "required key is missing"},
      {"    reference: {kind: sinking}\n" + sphere, "sinking", "reference.kind",
       "'sinking' is not one of: settling, floating, hindered"},
  };
  for (const Case& c : cases) {
    const auto [message, line] = error_and_line(c.body, c.needle);
    const std::string where =
        "scenario.yaml:" + std::to_string(line) + ": key 'participants.debris_dem." + c.key + "': ";
    EXPECT_NE(message.find(where), std::string::npos) << message << "\nexpected: " << where;
    EXPECT_NE(message.find(c.problem), std::string::npos) << message;
  }
}

// An STL file of the open box's five faces (ASCII, in mm) gives the DEM the same wall triangles as
// the declared `box:`, vertex for vertex; a missing or broken file is refused at its key.
TEST(DemConfig, AnStlBoxGivesTheSameWallsAsTheDeclaredBox) {
  const Eigen::Vector3d lo(0.0, 0.0, 0.0), hi(0.4, 0.2, 0.3);
  DemWorld declared(DemParameters{});
  const std::vector<int> ids = add_open_box(declared, lo, hi, Material{});
  ASSERT_EQ(ids.size(), 10u);
  const auto folder = write_scene("").parent_path();
  {
    std::ofstream stl(folder / "open_box.stl");
    stl << "solid open_box\n";
    for (const int id : ids) {
      stl << "  facet normal 0 0 0\n    outer loop\n";
      for (const auto& v : declared.triangle_vertices(id)) {
        stl << "      vertex " << 1000.0 * v.x() << " " << 1000.0 * v.y() << " " << 1000.0 * v.z()
            << "\n";
      }
      stl << "    endloop\n  endfacet\n";
    }
    stl << "endsolid open_box\n";
  }
  std::ofstream(folder / "broken.stl") << "solid broken\n  facet\n    vertex 0 0 x\n";
  const std::string sphere =
      "    elements:\n      - {kind: sphere, center: [0.2, 0.1, 0.05], diameter: 0.01, "
      "density: 1000}\n";
  const DebrisConfig from_stl =
      parse_body("    walls:\n      - {stl: open_box.stl, scale: 0.001}\n" + sphere);
  ASSERT_EQ(from_stl.walls.size(), 1u);
  const auto& mesh = from_stl.walls.front();
  ASSERT_EQ(mesh.size(), ids.size());
  for (std::size_t t = 0; t < ids.size(); ++t) {
    const auto v = declared.triangle_vertices(ids[t]);
    EXPECT_LT((mesh[t].a - v[0]).norm(), 1e-12) << t;
    EXPECT_LT((mesh[t].b - v[1]).norm(), 1e-12) << t;
    EXPECT_LT((mesh[t].c - v[2]).norm(), 1e-12) << t;
  }
  // Offset moves every vertex; the wall elements are the STL's triangles.
  const DebrisConfig moved = parse_body(
      "    walls:\n      - {stl: open_box.stl, scale: 0.001, offset: [1, 0, 0]}\n" + sphere);
  EXPECT_LT((moved.walls.front()[3].b - (mesh[3].b + Eigen::Vector3d::UnitX())).norm(), 1e-12);
  for (const auto& [body, needle, problem] :
       {std::tuple<std::string, std::string, std::string>{
            "    walls:\n      - {stl: nowhere.stl}\n" + sphere, "nowhere", "nowhere.stl"},
        {"    walls:\n      - {stl: broken.stl}\n" + sphere, "broken", "bad vertex"}}) {
    const auto [message, line] = error_and_line(body, needle);
    const std::string where =
        "scenario.yaml:" + std::to_string(line) + ": key 'participants.debris_dem.walls[0].stl': ";
    EXPECT_NE(message.find(where), std::string::npos) << message << "\nexpected: " << where;
    EXPECT_NE(message.find(problem), std::string::npos) << message;
  }
}

}  // namespace
}  // namespace cosim::dem
