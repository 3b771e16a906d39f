#include "util/process.h"

#include <fcntl.h>
#include <sched.h>
#include <spawn.h>
#include <sys/stat.h>
#include <sys/syscall.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <thread>

extern char** environ;

namespace rths::util {

struct ScopedCpuPin::Mask {
  cpu_set_t set;
};

namespace {

cpu_set_t calling_thread_mask() {
  cpu_set_t set;
  CPU_ZERO(&set);
  if (sched_getaffinity(0, sizeof set, &set) != 0)
    throw std::runtime_error(std::string("sched_getaffinity: ") + std::strerror(errno));
  return set;
}

void pin_calling_thread(int cpu) {
  cpu_set_t one;
  CPU_ZERO(&one);
  CPU_SET(cpu, &one);
  if (sched_setaffinity(0, sizeof one, &one) != 0)
    throw std::runtime_error("sched_setaffinity(CPU " + std::to_string(cpu) +
                             "): " + std::strerror(errno));
}

}  // namespace

ScopedCpuPin::ScopedCpuPin(int cpu) : previous_(std::make_unique<Mask>()) {
  previous_->set = calling_thread_mask();
  if (cpu < 0)
    for (int c = CPU_SETSIZE - 1; c >= 0 && cpu < 0; --c)
      if (CPU_ISSET(c, &previous_->set)) cpu = c;
  if (cpu < 0 || cpu >= CPU_SETSIZE || !CPU_ISSET(cpu, &previous_->set))
    throw std::runtime_error("cannot pin to CPU " + std::to_string(cpu) +
                             ": not in this process's allowed CPUs");
  pin_calling_thread(cpu);
  cpu_ = cpu;
}

ScopedCpuPin::~ScopedCpuPin() { sched_setaffinity(0, sizeof previous_->set, &previous_->set); }

ScopedCpuExclude::ScopedCpuExclude(int cpu) : previous_(std::make_unique<ScopedCpuPin::Mask>()) {
  previous_->set = calling_thread_mask();
  if (cpu < 0 || cpu >= CPU_SETSIZE || !CPU_ISSET(cpu, &previous_->set) ||
      CPU_COUNT(&previous_->set) < 2)
    return;
  cpu_set_t others = previous_->set;
  CPU_CLR(cpu, &others);
  active_ = sched_setaffinity(0, sizeof others, &others) == 0;
}

ScopedCpuExclude::~ScopedCpuExclude() {
  if (active_) sched_setaffinity(0, sizeof previous_->set, &previous_->set);
}

void isolate_calling_thread_on_cpu(int cpu) {
  if (cpu < 0 || cpu >= CPU_SETSIZE)
    throw std::runtime_error("cannot isolate CPU " + std::to_string(cpu) + ": no such CPU");
  // The CPUs the process runs on now: the union of its threads' masks. The loop's CPU need not
  // be among them (rths launch starts the coordinator off it); the kernel says whether it may be.
  cpu_set_t used = calling_thread_mask();
  const auto self = static_cast<pid_t>(syscall(SYS_gettid));
  std::vector<pid_t> others;
  for (const auto& task : std::filesystem::directory_iterator("/proc/self/task")) {
    const auto tid = static_cast<pid_t>(std::stol(task.path().filename().string()));
    if (tid == self) continue;
    others.push_back(tid);
    cpu_set_t mask;
    CPU_ZERO(&mask);
    if (sched_getaffinity(tid, sizeof mask, &mask) == 0) CPU_OR(&used, &used, &mask);
  }
  cpu_set_t rest = used;
  CPU_CLR(cpu, &rest);
  if (CPU_COUNT(&rest) == 0)
    throw std::runtime_error("cannot isolate CPU " + std::to_string(cpu) +
                             ": it is the only CPU this process may use");
  try {
    pin_calling_thread(cpu);
  } catch (const std::runtime_error& e) {
    throw std::runtime_error("cannot isolate CPU " + std::to_string(cpu) + ": " + e.what());
  }
  for (pid_t tid : others)
    if (sched_setaffinity(tid, sizeof rest, &rest) != 0 && errno != ESRCH)
      throw std::runtime_error("sched_setaffinity(thread " + std::to_string(tid) +
                               "): " + std::strerror(errno));
}

namespace {

int decode_status(int status) {
  if (WIFEXITED(status)) return WEXITSTATUS(status);
  if (WIFSIGNALED(status)) return 128 + WTERMSIG(status);
  return -1;
}

std::vector<std::string> merged_environment(const std::map<std::string, std::string>& overrides) {
  std::vector<std::string> env;
  for (char** entry = environ; entry != nullptr && *entry != nullptr; ++entry) {
    const std::string text(*entry);
    const auto eq = text.find('=');
    if (eq != std::string::npos && overrides.count(text.substr(0, eq)) != 0) continue;
    env.push_back(text);
  }
  for (const auto& [key, value] : overrides) env.push_back(key + "=" + value);
  return env;
}

std::vector<char*> c_strings(std::vector<std::string>& strings) {
  std::vector<char*> out;
  out.reserve(strings.size() + 1);
  for (auto& s : strings) out.push_back(s.data());
  out.push_back(nullptr);
  return out;
}

// Starts argv (PATH lookup) with stdout+stderr on output_fd, stdin /dev/null, empty signal mask,
// default SIGINT/TERM/PIPE, own process group. Throws naming argv[0] when it cannot start.
pid_t spawn(std::vector<std::string> argv, const std::map<std::string, std::string>& environment,
            int output_fd) {
  if (argv.empty()) throw std::invalid_argument("spawn: empty command");
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, STDIN_FILENO, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_adddup2(&actions, output_fd, STDOUT_FILENO);
  posix_spawn_file_actions_adddup2(&actions, output_fd, STDERR_FILENO);
  posix_spawnattr_t attributes;
  posix_spawnattr_init(&attributes);
  sigset_t empty, defaults;
  sigemptyset(&empty);
  sigemptyset(&defaults);
  sigaddset(&defaults, SIGINT);
  sigaddset(&defaults, SIGTERM);
  sigaddset(&defaults, SIGPIPE);
  posix_spawnattr_setsigmask(&attributes, &empty);
  posix_spawnattr_setsigdefault(&attributes, &defaults);
  posix_spawnattr_setpgroup(&attributes, 0);
  posix_spawnattr_setflags(&attributes,
                           POSIX_SPAWN_SETSIGMASK | POSIX_SPAWN_SETSIGDEF | POSIX_SPAWN_SETPGROUP);
  auto env_strings = merged_environment(environment);
  auto env = c_strings(env_strings);
  auto args = c_strings(argv);
  pid_t pid = -1;
  const int rc = posix_spawnp(&pid, args[0], &actions, &attributes, args.data(), env.data());
  posix_spawn_file_actions_destroy(&actions);
  posix_spawnattr_destroy(&attributes);
  if (rc != 0) throw std::runtime_error("cannot start '" + argv[0] + "': " + std::strerror(rc));
  return pid;
}

}  // namespace

ChildProcess::ChildProcess(const std::filesystem::path& program,
                           const std::vector<std::string>& args,
                           const std::filesystem::path& log_file, const ChildOptions& options)
    : name_(options.name.empty() ? program.filename().string() : options.name),
      log_file_(log_file) {
  std::vector<std::string> argv = options.prefix;
  argv.push_back(program.string());
  argv.insert(argv.end(), args.begin(), args.end());
  const int fd = log_file.empty()
                     ? ::open("/dev/null", O_WRONLY | O_CLOEXEC)
                     // Logs may name hosts, runs and tokens: for their owner alone.
                     : ::open(log_file.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0600);
  if (fd < 0)
    throw std::runtime_error("cannot create log " + log_file.string() + " for " + name_ + ": " +
                             std::strerror(errno));
  if (!log_file.empty()) ::fchmod(fd, 0600);  // a log that existed keeps no wider mode
  try {
    pid_ = spawn(argv, options.environment, fd);
  } catch (...) {
    ::close(fd);
    throw;
  }
  ::close(fd);
}

ChildProcess::ChildProcess(ChildProcess&& other) noexcept
    : pid_(other.pid_),
      exit_code_(other.exit_code_),
      name_(std::move(other.name_)),
      log_file_(std::move(other.log_file_)) {
  other.pid_ = -1;
}

ChildProcess::~ChildProcess() { terminate(kDestructorGrace); }

std::optional<int> ChildProcess::poll() {
  if (exit_code_ || pid_ <= 0) return exit_code_;
  int status = 0;
  if (::waitpid(pid_, &status, WNOHANG) == pid_) exit_code_ = decode_status(status);
  return exit_code_;
}

std::optional<int> ChildProcess::wait_for(std::chrono::milliseconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (!poll()) {
    if (std::chrono::steady_clock::now() >= deadline) return std::nullopt;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  return exit_code_;
}

int ChildProcess::wait() {
  if (pid_ <= 0) return -1;
  if (!exit_code_) {
    int status = 0;
    ::waitpid(pid_, &status, 0);
    exit_code_ = decode_status(status);
  }
  return *exit_code_;
}

void ChildProcess::signal(int sig) const {
  if (pid_ > 0 && !exit_code_) ::kill(pid_, sig);
}

int ChildProcess::terminate(std::chrono::milliseconds grace) {
  if (pid_ <= 0) return -1;
  if (poll()) return *exit_code_;
  ::kill(pid_, SIGTERM);
  if (wait_for(grace)) return *exit_code_;
  ::kill(pid_, SIGKILL);
  return wait();
}

std::string ChildProcess::log_tail(std::size_t max_bytes) const {
  std::ifstream in(log_file_, std::ios::binary);
  std::stringstream buffer;
  buffer << in.rdbuf();
  const std::string text = buffer.str();
  return text.size() <= max_bytes ? text : "..." + text.substr(text.size() - max_bytes);
}

std::string command_line(const std::vector<std::string>& argv) {
  std::string line;
  for (const auto& arg : argv) {
    if (!line.empty()) line += ' ';
    const bool quote = arg.empty() || arg.find_first_of(" \t'\"$") != std::string::npos;
    line += quote ? "'" + arg + "'" : arg;
  }
  return line;
}

bool tool_available(const std::string& tool) {
  if (tool.find('/') != std::string::npos) return ::access(tool.c_str(), X_OK) == 0;
  const char* path = std::getenv("PATH");
  std::stringstream dirs(path != nullptr ? path : "/usr/sbin:/usr/bin:/sbin:/bin");
  std::string dir;
  while (std::getline(dirs, dir, ':')) {
    if (!dir.empty() && ::access((dir + "/" + tool).c_str(), X_OK) == 0) return true;
  }
  return false;
}

CommandResult run_command(const std::vector<std::string>& argv, std::chrono::milliseconds timeout) {
  // A temporary file rather than a pipe: no reader thread, and no deadlock on large output.
  char name[] = "/tmp/rths-cmd-XXXXXX";
  const int fd = ::mkstemp(name);
  if (fd < 0) throw std::runtime_error(std::string("mkstemp: ") + std::strerror(errno));
  ::unlink(name);
  pid_t pid = -1;
  try {
    pid = spawn(argv, {}, fd);
  } catch (...) {
    ::close(fd);
    throw;
  }
  CommandResult result;
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  int status = 0;
  for (;;) {
    if (::waitpid(pid, &status, WNOHANG) == pid) {
      result.exit_code = decode_status(status);
      break;
    }
    if (std::chrono::steady_clock::now() > deadline) {
      ::kill(pid, SIGKILL);
      ::waitpid(pid, &status, 0);
      ::close(fd);
      throw std::runtime_error(command_line(argv) + ": timed out after " +
                               std::to_string(timeout.count()) + " ms");
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  ::lseek(fd, 0, SEEK_SET);
  char buffer[4096];
  ssize_t n = 0;
  while ((n = ::read(fd, buffer, sizeof buffer)) > 0)
    result.output.append(buffer, static_cast<std::size_t>(n));
  ::close(fd);
  return result;
}

std::string run_checked(const std::vector<std::string>& argv, std::chrono::milliseconds timeout) {
  auto result = run_command(argv, timeout);
  if (!result.ok()) {
    throw std::runtime_error(command_line(argv) + ": exit " + std::to_string(result.exit_code) +
                             ": " + result.output);
  }
  return result.output;
}

HeldStopSignals::HeldStopSignals() {
  sigemptyset(&held_);
  sigaddset(&held_, SIGINT);
  sigaddset(&held_, SIGTERM);
  sigaddset(&held_, SIGHUP);
  pthread_sigmask(SIG_BLOCK, &held_, &previous_);
}

HeldStopSignals::~HeldStopSignals() {
  timespec zero{0, 0};
  while (sigtimedwait(&held_, nullptr, &zero) > 0) {}
  pthread_sigmask(SIG_SETMASK, &previous_, nullptr);
}

bool HeldStopSignals::stop_requested() const {
  sigset_t pending;
  sigpending(&pending);
  return sigismember(&pending, SIGINT) == 1 || sigismember(&pending, SIGTERM) == 1 ||
         sigismember(&pending, SIGHUP) == 1;
}

std::filesystem::path executable_dir() {
  std::error_code ec;
  const auto exe = std::filesystem::read_symlink("/proc/self/exe", ec);
  return ec ? std::filesystem::current_path() : exe.parent_path();
}

std::filesystem::path find_program(const std::string& name, const std::string& build_subdir,
                                   const std::filesystem::path& explicit_dir) {
  std::vector<std::filesystem::path> candidates;
  if (!explicit_dir.empty()) {
    candidates.push_back(explicit_dir / name);
    candidates.push_back(explicit_dir / build_subdir / name);  // a build tree's root
  } else {
    if (const char* env = std::getenv("RTHS_BIN_DIR"); env != nullptr && *env != '\0') {
      candidates.push_back(std::filesystem::path(env) / name);
      candidates.push_back(std::filesystem::path(env) / build_subdir / name);
    }
    const auto here = executable_dir();
    candidates.push_back(here / name);
    candidates.push_back(here.parent_path() / build_subdir / name);
    candidates.push_back(here.parent_path().parent_path() / build_subdir / name);
    if (const char* path = std::getenv("PATH")) {
      std::stringstream dirs(path);
      std::string dir;
      while (std::getline(dirs, dir, ':'))
        if (!dir.empty()) candidates.push_back(std::filesystem::path(dir) / name);
    }
  }
  std::string looked;
  for (const auto& c : candidates) {
    if (::access(c.c_str(), X_OK) == 0) return std::filesystem::absolute(c);
    if (looked.size() < 400) looked += (looked.empty() ? "" : ", ") + c.string();
  }
  throw std::runtime_error("cannot find the program " + name + " (looked in " + looked +
                           "); build it, or pass its directory (--bin-dir or RTHS_BIN_DIR)");
}

NodePrograms find_node_programs(const std::filesystem::path& explicit_dir) {
  return {find_program("rths-coordinator", "coordinator", explicit_dir),
          find_program("rths-substructure-node", "substructure_nodes", explicit_dir),
          find_program("rths-actuator-emulator", "actuator_emulator", explicit_dir)};
}

}  // namespace rths::util
