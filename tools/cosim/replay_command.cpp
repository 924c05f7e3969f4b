#include "replay_command.hpp"

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cstring>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>

#include "cosim/coupler/event_log_file.hpp"
#include "cosim/output/files.hpp"
#include "cosim/output/point_series.hpp"
#include "cosim/replay/recording.hpp"

namespace cosim::tool {

namespace {

// Compares the frames of two output files bit for bit; returns the first difference. A run
// that failed was replayed only up to its last whole window: then the frames both files have
// are compared (the replay may add a frame at its end, the failed run never wrote its last).
std::string compare_outputs(const std::filesystem::path& expected,
                            const std::filesystem::path& actual, bool common_frames_only) {
  if (!std::filesystem::exists(actual)) return "missing from the replayed run";
  const int recorded_frames = output::count_point_frames(expected);
  const int replayed_frames = output::count_point_frames(actual);
  if (!common_frames_only && recorded_frames != replayed_frames) {
    return fmt::format("{} frames recorded, {} replayed", recorded_frames, replayed_frames);
  }
  const int frames = std::min(recorded_frames, replayed_frames);
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

// What the recorded run's summary says about how it ended (absent: assumed complete).
struct RecordedEnd {
  bool failed = false;
  int64_t windows_completed = 0;
  int64_t total_windows = 0;
  double simulated_time = 0.0;
  std::string failure;
  std::string record = "all";
};

RecordedEnd recorded_end(const std::filesystem::path& run_dir) {
  RecordedEnd end;
  std::ifstream in(run_dir / "summary.json");
  if (!in) return end;
  const auto summary = nlohmann::json::parse(in, nullptr, false);
  if (!summary.is_object()) return end;
  end.failed = !summary.value("ok", true);
  end.windows_completed = summary.value("windows_completed", int64_t{0});
  end.total_windows = summary.value("total_windows", int64_t{0});
  end.simulated_time = summary.value("simulated_time", 0.0);
  end.failure = summary.value("failure", std::string());
  end.record = summary.value("record", std::string("all"));
  return end;
}

// Refuses, before anything runs, a recording that cannot drive a replay.
void check_recording(const ReplayRequest& request, const std::filesystem::path& log,
                     const RecordedEnd& end) {
  // A replay plays the partners' recorded fields: say so plainly when the log cannot have them.
  if (!std::filesystem::exists(log)) {
    throw std::runtime_error(fmt::format(
        "{}: the run has no event log (recorded with --record none?); replay needs a run "
        "recorded with --record all",
        request.recorded_run.string()));
  }
  if (end.record != "all") {
    throw std::runtime_error(fmt::format(
        "{}: the run was recorded with --record {}: its log holds windows and reports but no "
        "field values, so its participants cannot be replayed; rerun it with --record all",
        log.string(), end.record));
  }
  if (end.failed && end.windows_completed < 1) {
    throw std::runtime_error(fmt::format(
        "{}: the recorded run failed before its first window was complete ({}): nothing to "
        "replay",
        request.recorded_run.string(), end.failure));
  }
}

// The recorded scene with every partner of `driven` replaced by a replay of its messages, cut
// at the last whole window when the recorded run failed.
YAML::Node replay_document(YAML::Node document, const scenario::Scene& recorded,
                           const scenario::ParticipantEntry& driven,
                           const std::filesystem::path& log, const RecordedEnd& end) {
  YAML::Node participants(YAML::NodeType::Map);
  for (const auto& entry : recorded.participants) {
    if (&entry == &driven) {
      participants[entry.name] = document["participants"][entry.name];
      continue;
    }
    YAML::Node replay(YAML::NodeType::Map);
    replay["participant"] = entry.acts_as;
    replay["log"] = log.string();
    participants["replay_" + entry.acts_as] = replay;
  }
  document["participants"] = participants;
  document["name"] = recorded.name;
  if (end.failed) {
    // Fixed windows: exactly the windows that completed. Adaptive ones: the time they reached.
    document["duration"] =
        recorded.coupling.adaptive_window
            ? end.simulated_time
            : static_cast<double>(end.windows_completed) * recorded.coupling.window;
  }
  return document;
}

// Compares every HDF5 output of the driven participant, both ways: a file only one run has is
// a difference, so a recorded run whose outputs were deleted is never reported identical.
std::vector<std::string> compare_output_folders(const std::filesystem::path& recorded,
                                                const std::filesystem::path& replayed,
                                                bool common_frames_only, int& compared) {
  std::vector<std::string> problems;
  auto outputs_of = [](const std::filesystem::path& folder) {
    std::set<std::string> names;
    if (!std::filesystem::is_directory(folder)) return names;
    for (const auto& file : std::filesystem::directory_iterator(folder)) {
      if (file.path().extension() == ".h5") names.insert(file.path().filename().string());
    }
    return names;
  };
  const auto recorded_files = outputs_of(recorded);
  for (const auto& name : outputs_of(replayed)) {
    if (!recorded_files.contains(name)) {
      problems.push_back(
          fmt::format("{}: missing from the recorded run ({} does not exist), so "
                      "the replay's output cannot be compared",
                      name, (recorded / name).string()));
    }
  }
  for (const auto& name : recorded_files) {
    ++compared;
    const auto problem = compare_outputs(recorded / name, replayed / name, common_frames_only);
    if (!problem.empty()) problems.push_back(name + ": " + problem);
  }
  return problems;
}

// Compares the replayed run with the recording and prints the verdict; returns the exit code.
int report_replay(const ReplayRequest& request, const scenario::ParticipantEntry& driven,
                  const RecordedEnd& end, replay::Recording expected, const RunOutcome& outcome) {
  if (end.failed) {
    // The windows after the last whole one may hold what some participants said before the
    // failure stopped the run; the replay never reached them.
    std::erase_if(expected.windows,
                  [&](const auto& window) { return window.first.window > end.windows_completed; });
  }
  const auto actual = replay::read_recording(outcome.run_dir / "events.lcmlog.zst", driven.acts_as);
  const auto mismatches = replay::compare_fields(expected, actual);
  std::size_t fields = 0;
  std::set<int64_t> windows;
  for (const auto& [key, window] : expected.windows) {
    fields += window.fields.size();
    windows.insert(key.window);
  }
  // Implicit schemes: every coupling iteration of every window.
  const std::string iterations =
      expected.windows.size() > windows.size()
          ? fmt::format(" ({} coupling iterations)", expected.windows.size())
          : std::string();
  int output_files = 0;
  const auto output_problems =
      compare_output_folders(request.recorded_run / driven.acts_as,
                             outcome.run_dir / driven.acts_as, end.failed, output_files);
  const std::string extent =
      end.failed ? fmt::format(" up to window {} of {} (the recorded run failed: {})",
                               end.windows_completed, end.total_windows, end.failure)
                 : std::string();
  fmt::print(
      "replayed '{}' against {}{}: {} windows{}, {} fields, {} output files compared bit for "
      "bit\n",
      driven.acts_as, request.recorded_run.string(), extent, windows.size(), iterations, fields,
      output_files);
  for (std::size_t i = 0; i < mismatches.size() && i < 10; ++i) {
    fmt::print("  {} field '{}': {}\n", replay::describe(mismatches[i].window), mismatches[i].field,
               mismatches[i].problem);
  }
  for (const auto& problem : output_problems) fmt::print("  output {}\n", problem);
  if (fields == 0) {
    fmt::print("  the recording holds no field of '{}': nothing to compare\n", driven.acts_as);
    return 1;
  }
  const bool identical = mismatches.empty() && output_problems.empty();
  fmt::print("{}: replay run folder {}\n", identical ? "IDENTICAL" : "DIFFERENT",
             outcome.run_dir.string());
  return identical ? 0 : 1;
}

}  // namespace

int replay_run(const ReplayRequest& request) {
  const auto recorded_scenario = request.recorded_run / "scenario.yaml";
  // Runs recorded before compression have a plain events.lcmlog.
  const auto recorded_log =
      std::filesystem::absolute(coupler::find_event_log(request.recorded_run)
                                    .value_or(request.recorded_run / "events.lcmlog.zst"));
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
  const RecordedEnd end = recorded_end(request.recorded_run);
  check_recording(request, recorded_log, end);
  if (driven->executable == "replay") {
    throw std::runtime_error(
        fmt::format("'{}' was itself a replay in that run", request.participant));
  }
  // Read before anything runs: a damaged log is named here (byte, record), not as a window the
  // replay process cannot find.
  auto expected = replay::read_recording(recorded_log, driven->acts_as);

  document = replay_document(document, recorded, *driven, recorded_log, end);
  const auto replay_scenario = std::filesystem::absolute(
      request.run.runs_dir / fmt::format("{}-replay-{}.yaml", recorded.name, driven->acts_as));
  const scenario::Scene scene =
      scenario::load_scene(document, replay_scenario, participant_parsers());
  RunRequest run = request.run;
  run.run_label = "replay-" + driven->acts_as;
  run.record_mode = coupler::RecordMode::all;  // the comparison reads the new run's fields
  check_run_request(scene, run);  // before the input file is written: no leftovers on an error
  std::filesystem::create_directories(request.run.runs_dir);
  {
    YAML::Emitter emitter;
    emitter << document;
    output::write_file_atomically(replay_scenario, std::string(emitter.c_str()) + "\n");
  }
  const RunOutcome outcome = run_scene(scene, run);
  std::filesystem::rename(replay_scenario, outcome.run_dir / "replay-input.yaml");
  if (outcome.interrupted_by != 0) {
    fmt::print(stderr, "{}\n", interruption_line(outcome));
    return outcome.exit_code;
  }
  if (!outcome.result.ok) {
    fmt::print(stderr, "replay run failed: {}\n", outcome.result.failure);
    return 1;
  }
  return report_replay(request, *driven, end, expected, outcome);
}

}  // namespace cosim::tool
