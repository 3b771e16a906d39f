#include "runtime/rt/fifo.h"

#include <sched.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <utility>

namespace rths::runtime {

namespace {

sched_param fifo_param(int priority) {
  if (priority < 1 || priority > 99)
    throw std::runtime_error(std::string("priority ") + std::to_string(priority) +
                             " is outside 1 to 99");
  sched_param param{};
  param.sched_priority = priority;
  return param;
}

pid_t calling_tid() { return static_cast<pid_t>(syscall(SYS_gettid)); }

struct Thread {
  pid_t tid;
  std::string name;
};

// This process's threads named in `names`, in thread-id order.
std::vector<Thread> named_threads(const std::vector<std::string>& names) {
  std::vector<Thread> found;
  for (const auto& task : std::filesystem::directory_iterator("/proc/self/task")) {
    std::ifstream comm(task.path() / "comm");
    std::string name;
    if (!std::getline(comm, name)) continue;  // the thread ended
    if (std::find(names.begin(), names.end(), name) == names.end()) continue;
    found.push_back({static_cast<pid_t>(std::stol(task.path().filename().string())), name});
  }
  std::sort(found.begin(), found.end(),
            [](const Thread& a, const Thread& b) { return a.tid < b.tid; });
  return found;
}

}  // namespace

FifoThreads::FifoThreads(int priority, std::string_view loop_name,
                         const std::vector<std::string>& names) {
  const std::string label = std::string("SCHED_FIFO ") + std::to_string(priority);
  std::vector<Thread> threads{{calling_tid(), std::string(loop_name)}};
  for (Thread& t : named_threads(names)) threads.push_back(std::move(t));
  std::string raised;
  try {
    const sched_param param = fifo_param(priority);
    for (const Thread& t : threads) {
      sched_param before{};
      const int policy = sched_getscheduler(t.tid);
      if (policy < 0 || sched_getparam(t.tid, &before) != 0) continue;  // it ended
      if (sched_setscheduler(t.tid, SCHED_FIFO, &param) != 0) {
        if (errno == ESRCH) continue;
        throw std::runtime_error("sched_setscheduler(" + t.name + "): " + std::strerror(errno));
      }
      saved_.push_back({t.tid, policy, before.sched_priority});
      raised += (raised.empty() ? "" : ", ") + t.name;
    }
  } catch (const std::exception& e) {
    restore();
    summary_ = label + " refused (" + e.what() + "); the threads run unprioritised";
    return;
  }
  summary_ = label + ": " + raised;
}

FifoThreads::~FifoThreads() { restore(); }

void FifoThreads::restore() {
  for (const Saved& s : saved_) {
    sched_param param{};
    param.sched_priority = s.priority;
    sched_setscheduler(s.tid, s.policy, &param);  // a thread that ended meanwhile: nothing to do
  }
  saved_.clear();
}

std::string scheduling_class(int tid) {
  switch (sched_getscheduler(static_cast<pid_t>(tid))) {
    case SCHED_FIFO: return "FF";
    case SCHED_RR: return "RR";
    case SCHED_OTHER: return "TS";
    case SCHED_BATCH: return "B";
    case SCHED_IDLE: return "IDL";
    default: return "?";
  }
}

}  // namespace rths::runtime
