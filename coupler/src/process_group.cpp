#include "cosim/coupler/process_group.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstring>
#include <stdexcept>
#include <thread>

namespace cosim::coupler {

std::string ChildExit::describe() const {
  if (interrupted) return fmt::format("the run was interrupted by SIG{}", sigabbrev_np(signal));
  if (signaled)
    return fmt::format("'{}' was killed by signal {} ({})", name, signal, strsignal(signal));
  return fmt::format("'{}' exited with code {}", name, exit_code);
}

std::filesystem::path executable_dir() {
  return std::filesystem::read_symlink("/proc/self/exe").parent_path();
}

ProcessGroup::~ProcessGroup() {
  terminate_all();
  wait_all(2.0);
}

void ProcessGroup::start(const std::string& name, const std::vector<std::string>& arguments,
                         const std::filesystem::path& log_file) {
  if (arguments.empty()) throw std::invalid_argument("no command for " + name);
  if (access(arguments[0].c_str(), X_OK) != 0) {
    throw std::runtime_error(
        fmt::format("cannot start '{}': {} is not an executable file", name, arguments[0]));
  }
  const int log_fd = open(log_file.c_str(), O_WRONLY | O_CREAT | O_APPEND | O_CLOEXEC, 0644);
  if (log_fd < 0) {
    throw std::runtime_error(
        fmt::format("cannot open log {}: {}", log_file.string(), strerror(errno)));
  }
  std::vector<char*> argv;
  for (const auto& argument : arguments) argv.push_back(const_cast<char*>(argument.c_str()));
  argv.push_back(nullptr);
  const pid_t pid = fork();
  if (pid < 0) {
    close(log_fd);
    throw std::runtime_error(fmt::format("fork for '{}' failed: {}", name, strerror(errno)));
  }
  if (pid == 0) {
    // Child: its own process group so a terminal Ctrl-C reaches the launcher, which then stops
    // the solvers in order.
    setpgid(0, 0);
    // The launcher holds SIGINT and SIGTERM for its watcher thread; a blocked mask survives
    // exec, and a solver must die of SIGTERM when the launcher stops it.
    sigset_t none;
    sigemptyset(&none);
    sigprocmask(SIG_SETMASK, &none, nullptr);
    // A launcher killed without cleaning up must not leave solvers computing for nobody.
    prctl(PR_SET_PDEATHSIG, SIGTERM);
    dup2(log_fd, STDOUT_FILENO);
    dup2(log_fd, STDERR_FILENO);
    execv(argv[0], argv.data());
    fmt::print(stderr, "exec {} failed: {}\n", argv[0], strerror(errno));
    _exit(127);
  }
  close(log_fd);
  children_.push_back(Child{name, pid, false});
}

void ProcessGroup::interrupt(int signal) {
  interrupt_signal_.store(signal);
}

std::vector<ChildExit> ProcessGroup::poll_exits() {
  std::vector<ChildExit> exits;
  if (const int signal = interrupt_signal_.exchange(0); signal != 0) {
    ChildExit exit{"cosim"};
    exit.signal = signal;
    exit.interrupted = true;
    exits.push_back(exit);
  }
  for (auto& child : children_) {
    if (child.exited) continue;
    int status = 0;
    const pid_t result = waitpid(child.pid, &status, WNOHANG);
    if (result != child.pid) continue;
    child.exited = true;
    ChildExit exit{child.name};
    if (WIFSIGNALED(status)) {
      exit.signaled = true;
      exit.signal = WTERMSIG(status);
    } else {
      exit.exit_code = WEXITSTATUS(status);
    }
    exits.push_back(exit);
  }
  return exits;
}

std::vector<ChildExit> ProcessGroup::wait_all(double seconds) {
  std::vector<ChildExit> exits;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
  while (true) {
    for (auto& exit : poll_exits()) exits.push_back(exit);
    bool any_running = false;
    for (const auto& child : children_) any_running = any_running || !child.exited;
    if (!any_running) return exits;
    if (std::chrono::steady_clock::now() > deadline) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  for (auto& child : children_) {
    if (!child.exited) kill(child.pid, SIGKILL);
  }
  for (auto& child : children_) {
    if (child.exited) continue;
    int status = 0;
    waitpid(child.pid, &status, 0);
    child.exited = true;
    exits.push_back(ChildExit{child.name, 0, SIGKILL, true});
  }
  return exits;
}

void ProcessGroup::terminate_all() {
  for (const auto& child : children_) {
    if (!child.exited) kill(child.pid, SIGTERM);
  }
}

bool ProcessGroup::running(const std::string& name) const {
  for (const auto& child : children_) {
    if (child.name == name) return !child.exited;
  }
  return false;
}

pid_t ProcessGroup::pid_of(const std::string& name) const {
  for (const auto& child : children_) {
    if (child.name == name) return child.pid;
  }
  return -1;
}

}  // namespace cosim::coupler
