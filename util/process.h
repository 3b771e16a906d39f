#pragma once
// Child processes for `rths launch`, `rths sites`, the deployment tooling and the tests: the one
// ChildProcess, the one program finder, one-shot commands (`ip ...`, `gnuplot ...`).
//
// Contracts:
//  - A ChildProcess runs `prefix... program args...` (argv[0] looked up in PATH when it has no
//    '/'); stdout and stderr go together to a log file (none: /dev/null), stdin is /dev/null. It
//    gets the parent's environment plus `environment` overrides, an empty signal mask and default
//    SIGINT/SIGTERM/SIGPIPE (the parent may hold them to stop its children in order), its own
//    process group (a Ctrl-C on the terminal reaches only the parent), and the CPU mask of the
//    thread that starts it (see ScopedCpuPin).
//  - It owns its pid: if it is still running when destroyed it gets SIGTERM, then SIGKILL after
//    kDestructorGrace, and is reaped. Nothing outlives its owner.
//  - Exit codes: the exit status, or 128 + signal number when a signal ended it.
//  - A program that cannot be started (missing, not executable, log not creatable) throws
//    std::runtime_error naming it, from the constructor.

#include <sys/types.h>

#include <chrono>
#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <signal.h>

namespace rths::util {

// Pins the calling thread to one CPU while it lives, so children started meanwhile (and all their
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

  struct Mask;  // a saved cpu_set_t

 private:
  std::unique_ptr<Mask> previous_;
  int cpu_ = -1;
};

// Keeps the calling thread, and children started meanwhile, off one CPU while it lives (its mask
// minus `cpu`); the previous mask comes back on destruction. It changes nothing (active() false)
// when `cpu` is not in the mask or is the only CPU in it.
class ScopedCpuExclude {
 public:
  explicit ScopedCpuExclude(int cpu);
  ScopedCpuExclude(const ScopedCpuExclude&) = delete;
  ScopedCpuExclude& operator=(const ScopedCpuExclude&) = delete;
  ~ScopedCpuExclude();
  bool active() const { return active_; }

 private:
  std::unique_ptr<ScopedCpuPin::Mask> previous_;
  bool active_ = false;
};

// Gives `cpu` to the calling thread alone within this process: pins the calling thread to it and
// moves every other thread of the process (a transport's receive threads, a record writer) to the
// allowed CPUs but it, so none of them can wake up on the loop's CPU and preempt the loop. Threads
// created later inherit their creator's mask. Throws std::runtime_error naming the call and the
// reason when the CPU cannot be had (not allowed, or the only one); a thread that ends meanwhile is
// skipped.
void isolate_calling_thread_on_cpu(int cpu);

// How a child is started besides its program and arguments.
struct ChildOptions {
  std::string name;                 // for messages; default the program's file name
  std::vector<std::string> prefix;  // run under this, e.g. {"ip","netns","exec","ns"}
  std::map<std::string, std::string> environment;  // overrides of the parent's environment
};

class ChildProcess {
 public:
  static constexpr std::chrono::milliseconds kDestructorGrace{1000};

  ChildProcess(const std::filesystem::path& program, const std::vector<std::string>& args,
               const std::filesystem::path& log_file, const ChildOptions& options = {});
  ChildProcess(ChildProcess&& other) noexcept;
  ChildProcess& operator=(ChildProcess&&) = delete;
  ChildProcess(const ChildProcess&) = delete;
  ~ChildProcess();

  pid_t pid() const { return pid_; }
  // Non-blocking: the exit code once the child has exited (reaping it), else nullopt.
  std::optional<int> poll();
  bool running() { return !poll().has_value(); }
  // Blocks up to `timeout`; nullopt if still running.
  std::optional<int> wait_for(std::chrono::milliseconds timeout);
  int wait();
  // Sends `sig` if the child has not been reaped yet.
  void signal(int sig) const;
  // SIGTERM, wait `grace`, then SIGKILL; returns the exit code. Idempotent.
  int terminate(std::chrono::milliseconds grace = std::chrono::seconds(2));

  const std::string& name() const { return name_; }
  const std::filesystem::path& log_file() const { return log_file_; }
  // The last `max_bytes` of the log, for error messages.
  std::string log_tail(std::size_t max_bytes = 2000) const;

 private:
  pid_t pid_ = -1;
  std::optional<int> exit_code_;
  std::string name_;
  std::filesystem::path log_file_;
};

struct CommandResult {
  int exit_code = -1;  // exit status, or 128 + signal number
  std::string output;  // stdout and stderr interleaved
  bool ok() const { return exit_code == 0; }
};

// Runs argv to completion and captures its output. Throws std::runtime_error when it cannot be
// started (naming the tool) or runs past `timeout` (then killed). A non-zero exit is returned.
CommandResult run_command(const std::vector<std::string>& argv,
                          std::chrono::milliseconds timeout = std::chrono::seconds(30));
// Same, but throws std::runtime_error "<command line>: exit N: <output>" on a non-zero exit.
std::string run_checked(const std::vector<std::string>& argv,
                        std::chrono::milliseconds timeout = std::chrono::seconds(30));
// Joins argv into one shell-like line for messages and logs.
std::string command_line(const std::vector<std::string>& argv);
// True when `tool` is an executable in PATH (or an executable path).
bool tool_available(const std::string& tool);

// Ctrl-C, SIGTERM and SIGHUP held pending while it lives and polled through stop_requested(), so
// that a launcher always stops its children (and removes what it built) in order; a signal
// received meanwhile is consumed on destruction, and the previous mask comes back.
class HeldStopSignals {
 public:
  HeldStopSignals();
  HeldStopSignals(const HeldStopSignals&) = delete;
  HeldStopSignals& operator=(const HeldStopSignals&) = delete;
  ~HeldStopSignals();
  bool stop_requested() const;

 private:
  sigset_t held_{}, previous_{};
};

// The directory of the running executable (/proc/self/exe).
std::filesystem::path executable_dir();

// Finds an rths program. With `explicit_dir`: there or in its <build_subdir>/ (a build tree's
// root) only. Otherwise, in order: $RTHS_BIN_DIR (and its <build_subdir>/); beside the running
// executable; <exe>/../<build_subdir>/ and <exe>/../../<build_subdir>/ (the build tree, from
// cli/ or tests/<folder>/); PATH. Returns an absolute path; throws naming the places looked at.
std::filesystem::path find_program(const std::string& name, const std::string& build_subdir,
                                   const std::filesystem::path& explicit_dir);

// The three programs of a distributed run, found by find_program.
struct NodePrograms {
  std::filesystem::path coordinator, substructure, actuator_emulator;
};
NodePrograms find_node_programs(const std::filesystem::path& explicit_dir);

}  // namespace rths::util
