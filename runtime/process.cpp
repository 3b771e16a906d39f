#include "runtime/process.h"

#include <fcntl.h>
#include <sched.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <sstream>
#include <stdexcept>
#include <thread>

namespace rths::runtime {

struct ScopedCpuPin::Mask {
  cpu_set_t set;
};

ScopedCpuPin::ScopedCpuPin(int cpu) : previous_(std::make_unique<Mask>()) {
  CPU_ZERO(&previous_->set);
  if (sched_getaffinity(0, sizeof previous_->set, &previous_->set) != 0)
    throw std::runtime_error(std::string("sched_getaffinity: ") + std::strerror(errno));
  if (cpu < 0)
    for (int c = CPU_SETSIZE - 1; c >= 0 && cpu < 0; --c)
      if (CPU_ISSET(c, &previous_->set)) cpu = c;
  if (cpu < 0 || cpu >= CPU_SETSIZE || !CPU_ISSET(cpu, &previous_->set))
    throw std::runtime_error("cannot pin to CPU " + std::to_string(cpu) +
                             ": not in this process's allowed CPUs");
  cpu_set_t one;
  CPU_ZERO(&one);
  CPU_SET(cpu, &one);
  if (sched_setaffinity(0, sizeof one, &one) != 0)
    throw std::runtime_error("sched_setaffinity(CPU " + std::to_string(cpu) +
                             "): " + std::strerror(errno));
  cpu_ = cpu;
}

ScopedCpuPin::~ScopedCpuPin() { sched_setaffinity(0, sizeof previous_->set, &previous_->set); }

ChildProcess::ChildProcess(const std::filesystem::path& program,
                           const std::vector<std::string>& args,
                           const std::filesystem::path& log_file)
    : name_(program.filename().string()) {
  if (access(program.c_str(), X_OK) != 0)
    throw std::runtime_error("cannot execute " + program.string() + ": " + std::strerror(errno));
  std::vector<std::string> argv_storage{program.string()};
  argv_storage.insert(argv_storage.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (auto& a : argv_storage) argv.push_back(a.data());
  argv.push_back(nullptr);
  // Opened before fork so that an error is reported here, not lost in the child.
  const int log = log_file.empty() ? -1 : open(log_file.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  if (!log_file.empty() && log < 0)
    throw std::runtime_error("cannot create log " + log_file.string() + ": " + std::strerror(errno));
  pid_ = fork();
  if (pid_ < 0) throw std::runtime_error("fork failed for " + program.string());
  if (pid_ == 0) {
    if (log >= 0) {
      dup2(log, STDOUT_FILENO);
      dup2(log, STDERR_FILENO);
      close(log);
    }
    execv(argv[0], argv.data());
    _exit(127);
  }
  if (log >= 0) close(log);
}

ChildProcess::ChildProcess(ChildProcess&& other) noexcept
    : pid_(other.pid_), status_(other.status_), name_(std::move(other.name_)) {
  other.pid_ = -1;
}

ChildProcess::~ChildProcess() {
  if (pid_ > 0 && !status_) {
    kill(pid_, SIGKILL);
    reap(true);
  }
}

std::optional<int> ChildProcess::reap(bool block) {
  if (status_ || pid_ <= 0) return status_;
  int status = 0;
  const pid_t r = waitpid(pid_, &status, block ? 0 : WNOHANG);
  if (r == pid_) {
    status_ = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  }
  return status_;
}

std::optional<int> ChildProcess::wait_for(std::chrono::milliseconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  for (;;) {
    if (auto s = reap(false)) return s;
    if (std::chrono::steady_clock::now() >= deadline) return std::nullopt;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
}

int ChildProcess::wait() { return *reap(true); }

void ChildProcess::signal(int sig) const {
  if (pid_ > 0 && !status_) kill(pid_, sig);
}

bool ChildProcess::running() { return !reap(false).has_value(); }

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
    const auto here = executable_dir();
    candidates.push_back(here / name);
    candidates.push_back(here.parent_path() / build_subdir / name);
    if (const char* path = std::getenv("PATH")) {
      std::stringstream dirs(path);
      std::string dir;
      while (std::getline(dirs, dir, ':'))
        if (!dir.empty()) candidates.push_back(std::filesystem::path(dir) / name);
    }
  }
  std::string looked;
  for (const auto& c : candidates) {
    if (access(c.c_str(), X_OK) == 0) return c;
    if (looked.size() < 400) looked += (looked.empty() ? "" : ", ") + c.string();
  }
  throw std::runtime_error("cannot find the program " + name + " (looked in " + looked +
                           "); build it or pass its directory");
}

}  // namespace rths::runtime
