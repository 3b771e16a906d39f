#pragma once
// Child processes for the deployment tooling: one-shot commands (`ip ...`) and long-running
// nodes (coordinator, substructure node, actuator emulator) started inside a namespace.
//
// Contracts:
//  - argv[0] is looked up in PATH (posix_spawnp); the child gets the parent's environment plus
//    `environment` overrides, and an empty signal mask (the parent may block SIGINT/SIGTERM to
//    wait for them synchronously).
//  - A ChildProcess owns its pid: if it is still running when destroyed it gets SIGTERM, then
//    SIGKILL after a grace period, and is reaped. Nothing outlives its owner.
//  - Output of a ChildProcess goes to a log file (stdout and stderr together), so a failed node
//    can be diagnosed after the fact.

#include <chrono>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace rths::deploy {

struct CommandResult {
  int exit_code = -1;   // exit status, or 128 + signal number when killed by a signal
  std::string output;   // stdout and stderr interleaved
  bool ok() const { return exit_code == 0; }
};

// Runs argv to completion and captures its output. Throws std::runtime_error when it cannot be
// started (e.g. the tool is missing), naming the tool. A non-zero exit is returned, not thrown.
CommandResult run_command(const std::vector<std::string>& argv,
                          std::chrono::milliseconds timeout = std::chrono::seconds(30));

// Same, but throws std::runtime_error "<command line>: exit N: <output>" on a non-zero exit.
std::string run_checked(const std::vector<std::string>& argv,
                        std::chrono::milliseconds timeout = std::chrono::seconds(30));

// Joins argv into one shell-like line for messages and logs.
std::string command_line(const std::vector<std::string>& argv);

// True when `tool` is an executable in PATH (or an executable path).
bool tool_available(const std::string& tool);

class ChildProcess {
 public:
  ChildProcess(std::string name, const std::vector<std::string>& argv,
               const std::map<std::string, std::string>& environment,
               const std::filesystem::path& log_file);
  ~ChildProcess();
  ChildProcess(const ChildProcess&) = delete;
  ChildProcess& operator=(const ChildProcess&) = delete;

  // Non-blocking: the exit code once the child has exited (reaping it), else nullopt.
  std::optional<int> poll();
  // Blocks up to `timeout`; nullopt if still running.
  std::optional<int> wait_for(std::chrono::milliseconds timeout);
  // SIGTERM, wait `grace`, then SIGKILL; returns the exit code. Idempotent.
  int terminate(std::chrono::milliseconds grace = std::chrono::seconds(2));

  const std::string& name() const { return name_; }
  const std::filesystem::path& log_file() const { return log_file_; }
  int pid() const { return pid_; }
  // The last `max_bytes` of the log, for error messages.
  std::string log_tail(std::size_t max_bytes = 2000) const;

 private:
  std::string name_;
  std::filesystem::path log_file_;
  int pid_ = -1;
  std::optional<int> exit_code_;
};

}  // namespace rths::deploy
