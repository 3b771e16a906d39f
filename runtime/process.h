#pragma once
// Child processes for `rths launch` and the tests: fork/exec with stdout+stderr to a log file,
// wait with a timeout, signal. The destructor kills (SIGKILL) and reaps a child still running,
// so no process outlives its owner by accident.

#include <sys/types.h>

#include <chrono>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace rths::runtime {

// Pins the calling thread to one CPU while it lives, so children forked meanwhile (and all their
// threads) start on that CPU alone; the thread's previous mask comes back on destruction.
// cpu < 0: the highest CPU the thread may run on now (CPU 0 tends to take more interrupts).
// Throws std::runtime_error when the CPU is not available to this thread.
class ScopedCpuPin {
 public:
  explicit ScopedCpuPin(int cpu = -1);
  ScopedCpuPin(const ScopedCpuPin&) = delete;
  ScopedCpuPin& operator=(const ScopedCpuPin&) = delete;
  ~ScopedCpuPin();
  int cpu() const { return cpu_; }

 private:
  struct Mask;
  std::unique_ptr<Mask> previous_;
  int cpu_ = -1;
};

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
