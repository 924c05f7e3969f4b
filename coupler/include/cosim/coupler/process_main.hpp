// What every solver process shares: its command line, the resolved scene, its own section,
// the participant connection, logging, fault injection for tests, and turning any error into a
// report to the coupler plus a non-zero exit code.
#pragma once

#include <filesystem>
#include <functional>
#include <memory>
#include <string>

#include "cosim/coupler/participant.hpp"
#include "cosim/scenario/scene.hpp"
#include "cosim/scenario/section.hpp"

namespace cosim::coupler {

class ProcessContext {
 public:
  scenario::Scene scene;
  std::string section_name;  // key of this process in `participants`
  std::string acts_as;       // name it publishes under
  std::filesystem::path run_dir;
  std::string program;  // the executable's kind ("fluid_mps", "replay", ...)
  // Checkpoint folder this run continues from (empty: a fresh start).
  std::filesystem::path restart_dir;
  std::unique_ptr<Participant> participant;

  // This process's section of the resolved scenario, for its own parser.
  scenario::Section section();
  // Output folder for this participant's files (created).
  std::filesystem::path output_dir() const;
  // Declares this process's frame for the handshake: the dimension, the span of a 2D one, and
  // the gravity [m/s^2, world frame] its physics actually uses. Until a process calls it, it
  // declares 3D under the scene's world gravity. Call before the first window. A process whose
  // windows report a stable dt (WindowResult::stable_dt > 0) declares `limits_window`.
  void declare_frame(int dimension, double span, const Eigen::Vector3d& gravity,
                     bool limits_window = false);
  // This process's file in a checkpoint folder (written by run_solver_loop).
  std::filesystem::path checkpoint_file(const std::filesystem::path& folder) const {
    return folder / (section_name + ".ckpt");
  }
  // The folder of the checkpoint after `window` in this run.
  std::filesystem::path checkpoint_folder(int64_t window) const;
  // Called at the start of every window: carries out an injected fault when one is due.
  void maybe_inject_fault(int64_t window) const;

 private:
  friend int run_process(int, char**, const std::string&,
                         const std::function<void(ProcessContext&)>&);
  YAML::Node document_;
  YAML::Node resolved_scratch_;
  std::string fault_kind_;
  int64_t fault_window_ = -1;
};

// Parses the common command line, connects, runs `body`, and reports failures. Returns the
// process exit code (0 on success).
int run_process(int argc, char** argv, const std::string& program,
                const std::function<void(ProcessContext&)>& body);

// Command line given to a solver process by the launcher.
std::vector<std::string> process_arguments(const std::filesystem::path& executable,
                                           const std::filesystem::path& resolved_scenario,
                                           const std::filesystem::path& run_dir,
                                           const std::string& section_name, const std::string& url,
                                           int64_t run_id, double loss_probability,
                                           const std::string& fault,
                                           const std::filesystem::path& restart_dir = {});

}  // namespace cosim::coupler
