// cosim: runs scenario bundles, validates them, and replays recorded runs.
#include <fmt/format.h>
#include <CLI/CLI.hpp>

#include <cmath>
#include <cstdlib>

#include "cosim/coupler/event_log_file.hpp"
#include "cosim_version.hpp"
#include "join_command.hpp"
#include "keys_command.hpp"
#include "network.hpp"
#include "plot.hpp"
#include "replay_command.hpp"
#include "runner.hpp"
#include "sweep.hpp"

namespace {

using namespace cosim;

// The shape PARTICIPANT:KIND@WINDOW only; what the scene allows is checked against it
// (tool::check_run_request), before any run folder is made.
std::map<std::string, std::string> parse_faults(const std::vector<std::string>& faults) {
  std::map<std::string, std::string> parsed;
  for (const auto& fault : faults) {
    const auto colon = fault.find(':');
    if (colon == std::string::npos || colon == 0 || fault.find('@', colon) == std::string::npos) {
      throw CLI::ValidationError(
          "--fault",
          "expected PARTICIPANT:KIND@WINDOW (e.g. vegetation_beam:exit@5), got '" + fault + "'");
    }
    const std::string name = fault.substr(0, colon);
    if (!parsed.emplace(name, fault.substr(colon + 1)).second) {
      throw CLI::ValidationError("--fault", "'" + name + "' is given twice; one fault each");
    }
  }
  return parsed;
}

// CLI::Range lets NaN through (every comparison with it is false): this one asks for a finite
// number first.
CLI::Validator finite_range(double low, double high) {
  return CLI::Validator(
      [low, high](std::string& text) -> std::string {
        double value = 0.0;
        std::size_t used = 0;
        try {
          value = std::stod(text, &used);
        } catch (const std::exception&) {
          used = 0;
        }
        if (used == 0 || used != text.size() || !std::isfinite(value) || value < low ||
            value > high) {
          return fmt::format("'{}' is not a finite number from {} to {}", text, low, high);
        }
        return "";
      },
      fmt::format("FINITE in [{} - {}]", low, high));
}

// Returns true when the caller should go on in this process.
bool ensure_network(const std::string& mode, int argc, char** argv) {
  if (mode == "host" || std::getenv(tool::kPrivateNetworkVariable)) return true;
  if (mode == "auto" && tool::multicast_available()) return true;
  const std::string problem = tool::reexec_in_private_network(argc, argv);
  throw std::runtime_error(problem);
}

// A run with participants on other hosts needs this host's network, with a multicast route.
void check_network_reaches_other_hosts(const std::string& mode) {
  if (mode == "private") {
    throw std::invalid_argument(
        "--network private cannot be combined with --remote: a private namespace reaches no "
        "other host");
  }
  if (!std::getenv(tool::kPrivateNetworkVariable) && !tool::multicast_available()) {
    throw std::runtime_error(
        "--remote: this host has no multicast route, so the other hosts cannot hear the run; add "
        "one on the interface that leads to them, e.g. `ip route add 224.0.0.0/4 dev eth0`");
  }
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"cosim: particle co-simulation of river flows with plants and debris"};
  app.set_version_flag("--version", std::string("cosim ") + tool::kVersion);
  app.require_subcommand(1);

  std::filesystem::path bundle;
  tool::RunRequest request;
  std::vector<std::string> faults;
  std::string network = "auto";
  std::vector<std::string> overrides;
  auto add_overrides = [&](CLI::App* command) {
    command->add_option("--set", overrides,
                        "override a scenario value: KEY=VALUE, e.g. "
                        "participants.fluid_mps.particle_spacing=0.004");
  };
  bool quiet = false;
  std::string record = "all";
  auto add_run_options = [&](CLI::App* command) {
    command->add_option("--runs-dir", request.runs_dir, "where run folders are made")
        ->default_val("runs");
    command
        ->add_option("--inject-loss", request.loss_probability,
                     "drop this fraction of the messages each process receives (testing)")
        ->check(finite_range(0.0, 0.5));
    command->add_option(
        "--fault", faults,
        "make a participant fail (testing): NAME:exit@W, NAME:hang@W, NAME:throw@W");
    command
        ->add_option("--network", network,
                     "auto: private network namespace when multicast is unavailable; host; "
                     "private")
        ->check(CLI::IsMember({"auto", "host", "private"}));
    command
        ->add_option(
            "--record", record,
            "what events.lcmlog.zst keeps: all (replayable), control (windows and reports, "
            "no field values), none (no log)")
        ->check(CLI::IsMember({"all", "control", "none"}));
    command->add_flag("--quiet", quiet, "no progress lines");
    command
        ->add_option("--progress-interval", request.progress_interval,
                     "seconds between progress lines (default: 1 on a terminal, where the line "
                     "is redrawn; 10 otherwise, as plain lines)")
        ->check(finite_range(0.0, 86400.0));
  };

  auto* run = app.add_subcommand("run", "run a scenario bundle");
  run->add_option("bundle", bundle, "scenario folder (or its scenario.yaml)")->required();
  std::string restart;
  run->add_option("--restart", restart,
                  "continue from a coupled checkpoint of RUN_FOLDER[@TIME] (the latest one "
                  "without @TIME)");
  add_run_options(run);
  add_overrides(run);
  run->add_option("--remote", request.remote,
                  "a participant started by hand on another host with `cosim join` (the line "
                  "to type is printed); repeat for several");
  run->add_option("--lcm-ttl", request.lcm_ttl,
                  "multicast time-to-live of a run with --remote (1: the local network)")
      ->default_val(1);
  run->add_option("--startup-timeout", request.startup_timeout,
                  "seconds every participant has to start (default 60, or 600 with --remote)")
      ->check(finite_range(1.0, 86400.0));

  auto* validate = app.add_subcommand("validate", "check a scenario bundle without running it");
  validate->add_option("bundle", bundle, "scenario folder (or its scenario.yaml)")->required();
  add_overrides(validate);

  tool::SweepRequest sweep;
  auto* sweep_command = app.add_subcommand(
      "sweep",
      "run a scene for several values of one parameter; tabulate metrics against run time");
  sweep_command->add_option("bundle", sweep.bundle, "scenario folder")->required();
  sweep_command->add_option("--vary", sweep.vary, "dotted key to vary")->required();
  sweep_command->add_option("--values", sweep.values, "its values, one run each")->required();
  add_run_options(sweep_command);
  add_overrides(sweep_command);
  bool no_plot = false;
  sweep_command->add_flag("--no-plot", no_plot,
                          "no error-vs-run-time figure (PNG beside the CSV, needs matplotlib)");

  tool::SpreadRequest spread;
  auto* spread_command = app.add_subcommand(
      "spread",
      "run a scene as it is and once per perturbation that changes nothing physical; tabulate "
      "how far each metric moves by itself");
  spread_command->add_option("bundle", spread.bundle, "scenario folder")->required();
  spread_command
      ->add_option("--perturb", spread.perturbations,
                   "KEY=VALUE, one run each: e.g. participants.fluid_mps.pcg_tolerance=1e-9, "
                   "participants.fluid_mps.courant=0.19")
      ->required();
  add_run_options(spread_command);
  add_overrides(spread_command);

  std::filesystem::path plot_dir;
  auto* plot_command = app.add_subcommand(
      "plot", "draw each metric's time series against its reference, as PNGs in the run folder");
  plot_command->add_option("run_dir", plot_dir, "a run folder")
      ->required()
      ->check(CLI::ExistingDirectory);

  tool::ReplayRequest replay;
  auto* replay_command = app.add_subcommand(
      "replay", "drive one solver from a recorded run and check its outputs bit for bit");
  replay_command->add_option("run_dir", replay.recorded_run, "a run folder")
      ->required()
      ->check(CLI::ExistingDirectory);
  replay_command->add_option("--participant", replay.participant, "the solver to drive")
      ->required();
  add_run_options(replay_command);

  std::filesystem::path export_run, export_file;
  auto* export_command = app.add_subcommand(
      "export-log", "write a run's event log as a plain LCM log (lcm-logger's format)");
  export_command->add_option("run_dir", export_run, "a run folder")
      ->required()
      ->check(CLI::ExistingDirectory);
  export_command->add_option("-o,--output", export_file,
                             "the .lcmlog to write (default: events.lcmlog in the run folder)");

  tool::add_keys_command(app);  // cosim keys [participant]: the key reference
  tool::JoinRequest join;
  auto* join_command = tool::add_join_command(app, join);
  CLI11_PARSE(app, argc, argv);
  try {
    request.faults = parse_faults(faults);
    request.show_progress = !quiet;
    request.record_mode = coupler::parse_record_mode(record);
    if (validate->parsed()) {
      const auto scene = tool::load_with_overrides(bundle, overrides);
      fmt::print("{}: valid ({} participants, {} windows of {} s)\n", scene.file.string(),
                 scene.participants.size(), scene.total_windows(), scene.coupling.window);
      return 0;
    }
    if (run->parsed()) {
      // Checked before the network, so a bad scenario is reported before anything starts.
      const auto scene = tool::load_with_overrides(bundle, overrides);
      tool::check_run_request(scene, request);
      if (!restart.empty() && !request.remote.empty()) {
        throw std::invalid_argument(
            "--restart cannot be combined with --remote yet: a remote participant's checkpoint "
            "is on its own host, and `cosim join` does not take one");
      }
      if (!restart.empty()) {
        request.restart = tool::parse_restart(restart);
        tool::resolve_restart(scene, *request.restart);  // refused before the network too
      }
      if (request.remote.empty()) {
        if (!ensure_network(network, argc, argv)) return 2;
      } else {
        check_network_reaches_other_hosts(network);
      }
      const auto outcome = tool::run_scene(scene, request);
      if (outcome.interrupted_by != 0) {
        fmt::print(stderr, "{}\n", tool::interruption_line(outcome));
        return outcome.exit_code;
      }
      tool::print_report(outcome.run_dir);
      return outcome.exit_code;
    }
    if (join_command->parsed()) tool::join_run(join);
    if (export_command->parsed()) {
      const auto log = coupler::find_event_log(export_run);
      if (!log) {
        throw std::invalid_argument(
            fmt::format("{} has no event log (events.lcmlog.zst): was it run with --record none?",
                        export_run.string()));
      }
      if (export_file.empty()) export_file = export_run / "events.lcmlog";
      if (std::filesystem::exists(export_file) && std::filesystem::equivalent(*log, export_file)) {
        fmt::print("{} is already a plain LCM log\n", log->string());
        return 0;
      }
      coupler::EventLogReader reader(*log);
      const int64_t events = coupler::write_lcm_log(reader, export_file);
      fmt::print("{} events written to {}\n", events, export_file.string());
      return 0;
    }
    if (plot_command->parsed()) {
      std::vector<std::string> notes;
      const auto files = tool::plot_run(plot_dir, notes);
      for (const auto& note : notes) fmt::print("{}\n", note);
      for (const auto& file : files) fmt::print("figure written to {}\n", file.string());
      return 0;
    }
    if (sweep_command->parsed()) {
      sweep.overrides = overrides;
      sweep.run = request;
      sweep.plot = !no_plot;
      if (!ensure_network(network, argc, argv)) return 2;
      return tool::sweep(sweep);
    }
    if (spread_command->parsed()) {
      spread.overrides = overrides;
      spread.run = request;
      if (!ensure_network(network, argc, argv)) return 2;
      return tool::spread(spread);
    }
    if (replay_command->parsed()) {
      if (!ensure_network(network, argc, argv)) return 2;
      replay.run = request;
      return tool::replay_run(replay);
    }
  } catch (const scenario::ScenarioError& error) {
    fmt::print(stderr, "error: {}\n", error.what());
    return 2;
  } catch (const std::exception& error) {
    fmt::print(stderr, "error: {}\n", error.what());
    return 2;
  }
  return 0;
}
