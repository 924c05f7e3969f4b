#include "cosim/scenario/scene.hpp"

#include "cosim/scenario/parameter_reader.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numbers>

namespace cosim::scenario {

std::string role_name(Role role) {
  return role == Role::flow ? "flow" : "solid";
}

const std::map<std::string, Role>& participant_roles() {
  static const std::map<std::string, Role> roles{{"fluid_mps", Role::flow},
                                                 {"prescribed_flow", Role::flow},
                                                 {"vegetation_beam", Role::solid},
                                                 {"debris_dem", Role::solid},
                                                 {"replay", Role::solid}};
  return roles;
}

int64_t Scene::total_windows() const {
  // A window shorter than the configured one would change the physics of the last step, so
  // the run covers at least `duration`.
  return static_cast<int64_t>(std::ceil(duration / coupling.window - 1e-9));
}

const ParticipantEntry* Scene::flow() const {
  for (const auto& entry : participants) {
    if (entry.role == Role::flow) return &entry;
  }
  return nullptr;
}

std::vector<const ParticipantEntry*> Scene::solids() const {
  std::vector<const ParticipantEntry*> result;
  for (const auto& entry : participants) {
    if (entry.role == Role::solid) result.push_back(&entry);
  }
  return result;
}

const ParticipantEntry& Scene::participant(const std::string& acts_as) const {
  for (const auto& entry : participants) {
    if (entry.acts_as == acts_as) return entry;
  }
  throw ScenarioError(fmt::format("{}: no participant '{}' in this scene", file.string(), acts_as));
}

Eigen::Vector3d slope_gravity(double slope_degrees, double g) {
  const double theta = slope_degrees * std::numbers::pi / 180.0;
  return {g * std::sin(theta), 0.0, -g * std::cos(theta)};
}

namespace {

// `world: {gravity: [gx, gy, gz]}`, or a bed slope, `slope_degrees` or `bed_slope` (sin theta),
// with `gravity_magnitude`; one of the three.
WorldSettings parse_world(Section world) {
  WorldSettings settings;
  if (world.has("slope_degrees") && world.has("bed_slope")) {
    world.fail("bed_slope", "give either 'slope_degrees' or 'bed_slope' (sin theta), not both");
  }
  if (world.has("gravity")) {
    for (const char* key : {"slope_degrees", "bed_slope", "gravity_magnitude"}) {
      if (world.has(key)) world.fail(key, "give either 'gravity' or the slope, not both");
    }
    settings.gravity = world.vector3("gravity");
    if (!settings.gravity.allFinite() || settings.gravity.norm() > 1000.0) {
      world.fail("gravity", "must be a finite vector of at most 1000 m/s^2");
    }
    return settings;
  }
  if (world.has("bed_slope")) {
    const double sine = world.number("bed_slope", Range::between(-0.866, 0.866));
    settings.slope_degrees = std::asin(sine) * 180.0 / std::numbers::pi;
  } else {
    settings.slope_degrees = world.number("slope_degrees", 0.0, Range::between(-60.0, 60.0));
  }
  const double g = world.number("gravity_magnitude", 9.81, Range::between(0.0, 1000.0));
  settings.gravity = slope_gravity(settings.slope_degrees, g);
  return settings;
}

CouplingSettings parse_coupling(Section coupling) {
  CouplingSettings settings;
  settings.scheme = coupling.text(
      "scheme", settings.scheme,
      {"serial-explicit", "parallel-explicit", "serial-implicit", "parallel-implicit"});
  if (settings.is_implicit() || coupling.has("implicit")) {
    if (!settings.is_implicit()) {
      coupling.fail("implicit", "is read only with scheme serial-implicit or parallel-implicit");
    }
    Section implicit = coupling.optional_child("implicit");
    read_parameters(implicit, settings.implicit);
  }
  read_parameters(coupling, settings.interface);
  if (settings.interface.resolved_plants && settings.scheme == "parallel-implicit") {
    coupling.fail("resolved_plants",
                  "is not iterated in the parallel-implicit scheme: use serial-implicit");
  }
  settings.window = coupling.number("window", Range::positive());
  settings.adaptive_window = coupling.flag("adaptive_window", settings.adaptive_window);
  // Solids hold the flow's fields over a window (and the flow the solids'); the key used to
  // promise a linear interpolation that no participant did.
  if (coupling.has("interpolation")) {
    coupling.fail("interpolation",
                  "is not a setting: every participant holds its partners' fields constant over "
                  "a window (explicit coupling); remove the key");
  }
  settings.timeout = coupling.number("timeout", settings.timeout, Range::between(0.1, 3600.0));
  settings.resend_interval =
      coupling.number("resend_interval", settings.resend_interval, Range::between(0.001, 10.0));
  settings.chunk_values =
      coupling.integer("chunk_values", settings.chunk_values, Range::between(16, 16384));
  return settings;
}

// parsers == nullptr: a resolved file, checked when its run started.
Scene parse_scene(const YAML::Node& document, const std::filesystem::path& file,
                  const std::map<std::string, ParticipantParser>* parsers) {
  const auto& kinds = participant_roles();
  Scene scene;
  scene.file = file;
  scene.resolved = YAML::Node(YAML::NodeType::Map);
  Section root = Section::root(document, file, scene.resolved);
  scene.name = root.text("name");
  // The name becomes the run folder's: letters, digits, '_', '-', '.', not starting with '.', so
  // a run never writes outside --runs-dir.
  const bool safe = !scene.name.empty() && scene.name.size() <= 100 && scene.name.front() != '.' &&
                    scene.name.find_first_not_of(
                        "abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ"
                        "0123456789_-.") == std::string::npos;
  if (!safe) {
    root.fail("name", "'" + scene.name +
                          "' cannot name a run folder: use 1-100 letters, digits, '_', '-' or "
                          "'.', not starting with '.'");
  }
  scene.description = root.text("description", "");
  scene.duration = root.number("duration", Range::positive());
  scene.coupling = parse_coupling(root.child("coupling"));
  scene.world = parse_world(root.optional_child("world"));
  scene.output_interval = root.number("output_interval", scene.duration / 100.0, Range::positive());
  read_parameters(root, scene.run);
  if (const double windows = std::ceil(scene.duration / scene.coupling.window - 1e-9);
      !(windows <= kMaxWindows)) {
    root.fail("duration", fmt::format("{:.6g} s in windows of {:.6g} s is {:.3g} windows, more "
                                      "than the {:.0e} a run may have (check duration and "
                                      "coupling.window)",
                                      scene.duration, scene.coupling.window, windows, kMaxWindows));
  }

  Section participants = root.child("participants");
  for (const std::string& name : participants.keys()) {
    // Several replays may stand in for several participants: replay, replay_fluid, ...
    const bool is_replay = name.rfind("replay", 0) == 0;
    const std::string kind_name = is_replay ? "replay" : name;
    const auto kind = kinds.find(kind_name);
    if (kind == kinds.end()) {
      std::string known;
      for (const auto& [known_name, unused] : kinds)
        known += (known.empty() ? "" : ", ") + known_name;
      participants.fail(name, "unknown participant; known participants: " + known);
    }
    Section section = participants.child(name);
    ParticipantEntry entry{name, kind_name, name, kind->second};
    if (is_replay) {
      // A replay stands in for the participant whose messages it plays back.
      entry.acts_as = section.text("participant");
      const auto replayed = kinds.find(entry.acts_as);
      if (replayed == kinds.end() || entry.acts_as == "replay") {
        section.fail("participant", "cannot replay unknown participant '" + entry.acts_as + "'");
      }
      entry.role = replayed->second;
    }
    if (parsers) {
      const auto parser = parsers->find(kind_name);
      if (parser == parsers->end())
        participants.fail(name, "this program cannot run '" + name + "'");
      parser->second(section, scene);
    }
    scene.participants.push_back(entry);
  }
  if (scene.participants.empty()) participants.fail("participants", "a scene needs a participant");
  int flows = 0;
  for (const auto& entry : scene.participants) flows += entry.role == Role::flow;
  if (flows > 1) participants.fail("participants", "a scene has at most one flow provider");
  for (std::size_t i = 0; i < scene.participants.size(); ++i) {
    for (std::size_t j = i + 1; j < scene.participants.size(); ++j) {
      if (scene.participants[i].acts_as == scene.participants[j].acts_as) {
        participants.fail(scene.participants[j].name, "two participants would both act as '" +
                                                          scene.participants[j].acts_as + "'");
      }
    }
  }
  if (scene.coupling.interface.resolved_plants) {
    const bool fluid = std::any_of(scene.participants.begin(), scene.participants.end(),
                                   [](const auto& e) { return e.acts_as == "fluid_mps"; });
    const bool plants = std::any_of(scene.participants.begin(), scene.participants.end(),
                                    [](const auto& e) { return e.acts_as == "vegetation_beam"; });
    if (!fluid || !plants) {
      root.child("coupling")
          .fail("resolved_plants", "needs fluid_mps and vegetation_beam among the participants");
    }
  }
  if (scene.coupling.adaptive_window && flows == 0) {
    root.child("coupling").fail("adaptive_window", "needs a flow provider to set the window");
  }
  std::stable_partition(scene.participants.begin(), scene.participants.end(),
                        [](const ParticipantEntry& entry) { return entry.role == Role::flow; });
  if (parsers) root.finish();
  return scene;
}

}  // namespace

Scene load_scene(const std::filesystem::path& bundle_or_file,
                 const std::map<std::string, ParticipantParser>& parsers) {
  const std::filesystem::path file = std::filesystem::is_directory(bundle_or_file)
                                         ? bundle_or_file / "scenario.yaml"
                                         : bundle_or_file;
  return parse_scene(load_yaml_file(file), file, &parsers);
}

Scene load_scene(const YAML::Node& document, const std::filesystem::path& file,
                 const std::map<std::string, ParticipantParser>& parsers) {
  return parse_scene(document, file, &parsers);
}

void apply_override(YAML::Node& document, const std::string& dotted_key, const std::string& value) {
  std::vector<std::string> keys;
  std::size_t start = 0;
  while (true) {
    const auto dot = dotted_key.find('.', start);
    keys.push_back(dotted_key.substr(start, dot - start));
    if (dot == std::string::npos) break;
    start = dot + 1;
  }
  for (const auto& key : keys) {
    if (key.empty()) throw ScenarioError("override '" + dotted_key + "': empty key");
  }
  YAML::Node parsed;
  try {
    parsed = YAML::Load(value);
  } catch (const YAML::Exception& error) {
    throw ScenarioError("override '" + dotted_key + "=" + value + "': " + error.msg);
  }
  // yaml-cpp nodes are handles: walk down by reassigning through a chain of copies.
  std::vector<YAML::Node> chain{document};
  // A numeric key indexes a list: participants.vegetation_beam.plants.0.links
  auto list_index = [&](const YAML::Node& node, const std::string& key) -> int {
    if (!node.IsSequence()) return -1;
    if (key.find_first_not_of("0123456789") != std::string::npos) {
      throw ScenarioError("override '" + dotted_key + "': '" + key + "' must index a list");
    }
    const int index = std::stoi(key);
    if (index >= static_cast<int>(node.size())) {
      throw ScenarioError("override '" + dotted_key + "': the list has " +
                          std::to_string(node.size()) + " entries");
    }
    return index;
  };
  for (std::size_t i = 0; i + 1 < keys.size(); ++i) {
    if (const int index = list_index(chain.back(), keys[i]); index >= 0) {
      chain.push_back(chain.back()[index]);
      continue;
    }
    YAML::Node next = chain.back()[keys[i]];
    if (next && !next.IsMap() && !next.IsSequence()) {
      throw ScenarioError("override '" + dotted_key + "': '" + keys[i] + "' is not a mapping");
    }
    if (!next) chain.back()[keys[i]] = YAML::Node(YAML::NodeType::Map);
    chain.push_back(chain.back()[keys[i]]);
  }
  if (const int index = list_index(chain.back(), keys.back()); index >= 0) {
    chain.back()[index] = parsed;
  } else {
    // The key is written anew, so it has no line in the file: an error about it then says it
    // came from the command line instead of pointing at the file's line with the old value.
    chain.back().remove(keys.back());
    chain.back()[keys.back()] = parsed;
  }
}

Scene load_resolved_scene(const std::filesystem::path& file) {
  return parse_scene(load_yaml_file(file), file, nullptr);
}

}  // namespace cosim::scenario
