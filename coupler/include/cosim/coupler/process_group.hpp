// Child processes of a run: started with their output in a log file, watched for early exits,
// and stopped together when the run ends or fails.
#pragma once

#include <sys/types.h>

#include <atomic>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace cosim::coupler {

struct ChildExit {
  std::string name;
  int exit_code = 0;  // valid when !signaled
  int signal = 0;     // valid when signaled
  bool signaled = false;
  // Not a child at all: the run was interrupted (SIGINT/SIGTERM to cosim), `signal` says how.
  bool interrupted = false;
  std::string describe() const;
};

class ProcessGroup {
 public:
  ProcessGroup() = default;
  ~ProcessGroup();
  ProcessGroup(const ProcessGroup&) = delete;
  ProcessGroup& operator=(const ProcessGroup&) = delete;

  // Starts `arguments[0]` with stdout and stderr appended to `log_file`.
  void start(const std::string& name, const std::vector<std::string>& arguments,
             const std::filesystem::path& log_file);
  // Reaps children that exited since the last call.
  std::vector<ChildExit> poll_exits();
  // Waits up to `seconds` for every child to exit, then kills the rest.
  std::vector<ChildExit> wait_all(double seconds);
  void terminate_all();
  // Asks the run to stop: the next poll_exits() reports, once, an exit with `interrupted` set,
  // so the coupler aborts the run the way it does when a child dies. Callable from any thread.
  void interrupt(int signal);
  bool running(const std::string& name) const;
  pid_t pid_of(const std::string& name) const;

 private:
  struct Child {
    std::string name;
    pid_t pid = -1;
    bool exited = false;
  };
  std::vector<Child> children_;
  std::atomic<int> interrupt_signal_{0};
};

// The folder holding this executable (solver executables are installed beside `cosim`).
std::filesystem::path executable_dir();

}  // namespace cosim::coupler
