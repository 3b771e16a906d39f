#pragma once
// Child processes for `rths launch` and the tests: fork/exec with stdout+stderr to a log file,
// wait with a timeout, signal. The destructor kills (SIGKILL) and reaps a child still running,
// so no process outlives its owner by accident.

#include <sys/types.h>

#include <chrono>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace rths::runtime {

class ChildProcess {
 public:
  // Throws std::runtime_error naming the program when it is missing or fork fails.
  ChildProcess(const std::filesystem::path& program, const std::vector<std::string>& args,
               const std::filesystem::path& log_file);
  ChildProcess(ChildProcess&& other) noexcept;
  ChildProcess& operator=(ChildProcess&&) = delete;
  ChildProcess(const ChildProcess&) = delete;
  ~ChildProcess();

  pid_t pid() const { return pid_; }
  // Exit code, or 128 + signal when killed; nullopt if still running after `timeout`.
  std::optional<int> wait_for(std::chrono::milliseconds timeout);
  int wait();
  void signal(int sig) const;
  bool running();
  const std::string& name() const { return name_; }

 private:
  std::optional<int> reap(bool block);
  pid_t pid_ = -1;
  std::optional<int> status_;
  std::string name_;
};

// The directory of the running executable (/proc/self/exe).
std::filesystem::path executable_dir();

// Finds an rths program: in `explicit_dir` (or its <build_subdir>/) if given; else beside the running executable; else
// in the build tree's sibling folder (../<build_subdir>/); else on PATH. Throws naming the places
// looked at.
std::filesystem::path find_program(const std::string& name, const std::string& build_subdir,
                                   const std::filesystem::path& explicit_dir);

}  // namespace rths::runtime
