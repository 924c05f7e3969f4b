#include "replay_command.hpp"

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include <fstream>
#include <nlohmann/json.hpp>

#include "cosim/output/point_series.hpp"
#include "cosim/replay/recording.hpp"

namespace cosim::tool {

namespace {

// Compares every frame of two output files bit for bit; returns the first difference.
std::string compare_outputs(const std::filesystem::path& expected,
                            const std::filesystem::path& actual) {
  if (!std::filesystem::exists(actual)) return "missing from the replayed run";
  const int frames = output::count_point_frames(expected);
  if (frames != output::count_point_frames(actual)) {
    return fmt::format("{} frames recorded, {} replayed", frames,
                       output::count_point_frames(actual));
  }
  auto same_bits = [](const auto& a, const auto& b) {
    return a.size() == b.size() &&
           (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(a[0])) == 0);
  };
  for (int index = 0; index < frames; ++index) {
    const auto a = output::read_point_frame(expected, index);
    const auto b = output::read_point_frame(actual, index);
    if (a.time != b.time || !same_bits(a.positions, b.positions)) {
      return fmt::format("frame {} positions differ", index);
    }
    for (const auto& [name, values] : a.scalars) {
      if (!b.scalars.contains(name) || !same_bits(values, b.scalars.at(name))) {
        return fmt::format("frame {} scalar '{}' differs", index, name);
      }
    }
    for (const auto& [name, values] : a.vectors) {
      if (!b.vectors.contains(name) || !same_bits(values, b.vectors.at(name))) {
        return fmt::format("frame {} vector '{}' differs", index, name);
      }
    }
  }
  return "";
}

}  // namespace

int replay_run(const ReplayRequest& request) {
  const auto recorded_scenario = request.recorded_run / "scenario.yaml";
  const auto recorded_log = std::filesystem::absolute(request.recorded_run / "events.lcmlog");
  YAML::Node document = scenario::load_yaml_file(recorded_scenario);
  const scenario::Scene recorded = scenario::load_resolved_scene(recorded_scenario);

  const scenario::ParticipantEntry* driven = nullptr;
  for (const auto& entry : recorded.participants) {
    if (entry.name == request.participant || entry.acts_as == request.participant) driven = &entry;
  }
  if (!driven) {
    throw std::runtime_error(fmt::format("{}: the recorded run has no participant '{}'",
                                         recorded_scenario.string(), request.participant));
  }
  // A replay plays the partners' recorded fields: say so plainly when the log cannot have them.
  if (!std::filesystem::exists(recorded_log)) {
    throw std::runtime_error(fmt::format(
        "{}: the run has no event log (recorded with --record none?); replay needs a run "
        "recorded with --record all",
        request.recorded_run.string()));
  }
  if (std::ifstream in(request.recorded_run / "summary.json"); in) {
    const auto summary = nlohmann::json::parse(in, nullptr, false);
    if (summary.is_object() && summary.value("record", "all") != "all") {
      throw std::runtime_error(fmt::format(
          "{}: the run was recorded with --record {}: its log holds windows and reports but no "
          "field values, so its participants cannot be replayed; rerun it with --record all",
          recorded_log.string(), summary.value("record", "")));
    }
  }
  if (driven->executable == "replay") {
    throw std::runtime_error(
        fmt::format("'{}' was itself a replay in that run", request.participant));
  }
  // Every partner becomes a replay of its recorded messages.
  YAML::Node participants(YAML::NodeType::Map);
  for (const auto& entry : recorded.participants) {
    if (&entry == driven) {
      participants[entry.name] = document["participants"][entry.name];
      continue;
    }
    YAML::Node replay(YAML::NodeType::Map);
    replay["participant"] = entry.acts_as;
    replay["log"] = recorded_log.string();
    participants["replay_" + entry.acts_as] = replay;
  }
  document["participants"] = participants;
  document["name"] = recorded.name;
  std::filesystem::create_directories(request.run.runs_dir);
  const auto replay_scenario = std::filesystem::absolute(
      request.run.runs_dir / fmt::format("{}-replay-{}.yaml", recorded.name, driven->acts_as));
  {
    std::ofstream out(replay_scenario);
    YAML::Emitter emitter;
    emitter << document;
    out << emitter.c_str() << "\n";
  }
  const scenario::Scene scene = scenario::load_scene(replay_scenario, participant_parsers());
  RunRequest run = request.run;
  run.run_label = "replay-" + driven->acts_as;
  run.record_mode = coupler::RecordMode::all;  // the comparison reads the new run's fields
  const RunOutcome outcome = run_scene(scene, run);
  std::filesystem::rename(replay_scenario, outcome.run_dir / "replay-input.yaml");
  if (!outcome.result.ok) {
    fmt::print(stderr, "replay run failed: {}\n", outcome.result.failure);
    return 1;
  }

  const auto expected = replay::read_recording(recorded_log, driven->acts_as);
  const auto actual = replay::read_recording(outcome.run_dir / "events.lcmlog", driven->acts_as);
  const auto mismatches = replay::compare_fields(expected, actual);
  std::size_t fields = 0;
  for (const auto& [index, window] : expected.windows) fields += window.fields.size();
  std::vector<std::string> output_problems;
  int output_files = 0;
  const auto recorded_outputs = request.recorded_run / driven->acts_as;
  if (std::filesystem::is_directory(recorded_outputs)) {
    for (const auto& file : std::filesystem::directory_iterator(recorded_outputs)) {
      if (file.path().extension() != ".h5") continue;
      ++output_files;
      const auto problem =
          compare_outputs(file.path(), outcome.run_dir / driven->acts_as / file.path().filename());
      if (!problem.empty())
        output_problems.push_back(file.path().filename().string() + ": " + problem);
    }
  }
  fmt::print(
      "replayed '{}' against {}: {} windows, {} fields, {} output files compared bit for bit\n",
      driven->acts_as, request.recorded_run.string(), expected.windows.size(), fields,
      output_files);
  for (std::size_t i = 0; i < mismatches.size() && i < 10; ++i) {
    fmt::print("  window {} field '{}': {}\n", mismatches[i].window, mismatches[i].field,
               mismatches[i].problem);
  }
  for (const auto& problem : output_problems) fmt::print("  output {}\n", problem);
  if (fields == 0) {
    fmt::print("  the recording holds no field of '{}': nothing to compare\n", driven->acts_as);
    return 1;
  }
  const bool identical = mismatches.empty() && output_problems.empty();
  fmt::print("{}: replay run folder {}\n", identical ? "IDENTICAL" : "DIFFERENT",
             outcome.run_dir.string());
  return identical ? 0 : 1;
}

}  // namespace cosim::tool
