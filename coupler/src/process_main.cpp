#include "cosim/coupler/process_main.hpp"

#include <fmt/format.h>
#include <signal.h>
#include <spdlog/spdlog.h>
#include <CLI/CLI.hpp>

#include <cstdlib>

#include "cosim/coupler/frame.hpp"

namespace cosim::coupler {

scenario::Section ProcessContext::section() {
  resolved_scratch_ = YAML::Node(YAML::NodeType::Map);
  scenario::Section root = scenario::Section::root(document_, scene.file, resolved_scratch_);
  return root.child("participants").child(section_name);
}

std::filesystem::path ProcessContext::output_dir() const {
  const auto folder = run_dir / acts_as;
  std::filesystem::create_directories(folder);
  return folder;
}

std::filesystem::path ProcessContext::checkpoint_folder(int64_t window) const {
  return run_dir / "checkpoints" / fmt::format("window_{:08d}", window);
}

void ProcessContext::declare_frame(int dimension, double span, const Eigen::Vector3d& gravity,
                                   bool limits_window) {
  FrameDeclaration declaration;
  declaration.limits_window = limits_window;
  declaration.dimension = dimension;
  declaration.span = dimension == 2 ? span : 0.0;
  declaration.gravity = gravity;
  participant->declare(declaration.to_json());
}

void ProcessContext::maybe_inject_fault(int64_t window) const {
  if (fault_window_ < 0 || window != fault_window_) return;
  if (fault_kind_ == "exit") {
    spdlog::error("injected fault: exiting in window {}", window);
    std::_Exit(3);
  }
  if (fault_kind_ == "hang") {
    spdlog::error("injected fault: hanging in window {}", window);
    // Stops every thread, heartbeat included, exactly like a process stuck in the kernel.
    raise(SIGSTOP);
  }
  if (fault_kind_ == "throw") throw std::runtime_error("injected fault");
}

std::vector<std::string> process_arguments(const std::filesystem::path& executable,
                                           const std::filesystem::path& resolved_scenario,
                                           const std::filesystem::path& run_dir,
                                           const std::string& section_name, const std::string& url,
                                           int64_t run_id, double loss_probability,
                                           const std::string& fault,
                                           const std::filesystem::path& restart_dir) {
  std::vector<std::string> arguments{executable.string(),
                                     "--scenario",
                                     resolved_scenario.string(),
                                     "--run-dir",
                                     run_dir.string(),
                                     "--name",
                                     section_name,
                                     "--lcm-url",
                                     url,
                                     "--run-id",
                                     std::to_string(run_id),
                                     "--inject-loss",
                                     fmt::format("{}", loss_probability)};
  if (!fault.empty()) {
    arguments.push_back("--fault");
    arguments.push_back(fault);
  }
  if (!restart_dir.empty()) {
    arguments.push_back("--restart");
    arguments.push_back(restart_dir.string());
  }
  return arguments;
}

int run_process(int argc, char** argv, const std::string& program,
                const std::function<void(ProcessContext&)>& body) {
  CLI::App app{program + ": a participant of a coupled run, started by `cosim run`"};
  std::filesystem::path scenario_file;
  std::string section_name = program;
  std::string url;
  int64_t run_id = 0;
  double loss = 0.0;
  std::string fault;
  std::filesystem::path run_dir;
  std::filesystem::path restart_dir;
  app.add_option("--scenario", scenario_file, "resolved scenario of the run")->required();
  app.add_option("--run-dir", run_dir, "run folder")->required();
  app.add_option("--name", section_name, "this process's key under participants");
  app.add_option("--lcm-url", url, "LCM URL of the run")->required();
  app.add_option("--run-id", run_id, "run id")->required();
  app.add_option("--inject-loss", loss, "drop this fraction of received messages (tests)")
      ->check(CLI::Range(0.0, 0.9));
  app.add_option("--restart", restart_dir, "checkpoint folder to continue from");
  app.add_option("--fault", fault, "test fault: exit@W, hang@W or throw@W (window W)");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& error) {
    return app.exit(error);
  }
  spdlog::set_pattern("[%H:%M:%S.%e] [" + section_name + "] [%l] %v");

  ProcessContext context;
  std::unique_ptr<Participant> participant;
  try {
    context.scene = scenario::load_resolved_scene(scenario_file);
    context.document_ = scenario::load_yaml_file(scenario_file);
    context.section_name = section_name;
    context.run_dir = run_dir;
    context.program = program;
    context.restart_dir = restart_dir;
    bool found = false;
    for (const auto& entry : context.scene.participants) {
      if (entry.name == section_name) {
        context.acts_as = entry.acts_as;
        found = true;
      }
    }
    if (!found) {
      throw std::runtime_error(fmt::format("{}: the scene has no participant '{}'",
                                           scenario_file.string(), section_name));
    }
    if (!fault.empty()) {
      const auto at = fault.find('@');
      if (at == std::string::npos) throw std::runtime_error("--fault expects KIND@WINDOW");
      context.fault_kind_ = fault.substr(0, at);
      context.fault_window_ = std::stoll(fault.substr(at + 1));
    }
    ParticipantOptions options;
    options.name = context.acts_as;
    options.url = url;
    options.run_id = run_id;
    options.timeout = context.scene.coupling.timeout;
    options.resend_interval = context.scene.coupling.resend_interval;
    options.chunk_values = context.scene.coupling.chunk_values;
    options.loss_probability = loss;
    options.loss_seed = std::hash<std::string>{}(section_name) ^ static_cast<uint64_t>(run_id);
    options.rollback = context.scene.coupling.is_implicit();
    context.participant = std::make_unique<Participant>(options);
    context.declare_frame(3, 0.0, context.scene.world.gravity);
  } catch (const std::exception& error) {
    spdlog::error("{}", error.what());
    return 2;
  }
  try {
    body(context);
    return 0;
  } catch (const CouplingError& error) {
    spdlog::error("{}", error.what());
    return 4;
  } catch (const std::exception& error) {
    spdlog::error("{}", error.what());
    context.participant->failed(error.what());
    return 1;
  }
}

}  // namespace cosim::coupler
