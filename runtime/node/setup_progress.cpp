#include "runtime/node/setup_progress.h"

#include <chrono>
#include <cstdio>
#include <optional>
#include <utility>

namespace rths::runtime {

SetupProgress::SetupProgress(std::string label, util::ProgressPacing pacing, Print print)
    : label_(std::move(label)), print_(std::move(print)), pace_(std::move(pacing)) {}

SetupProgress::~SetupProgress() { stop_watch(); }

void SetupProgress::phase(std::string what) {
  poll();  // the phase that ends, if a line is due
  std::lock_guard guard(mutex_);
  phase_ = std::move(what);
}

void SetupProgress::poll() {
  std::unique_lock guard(mutex_);
  const std::optional<double> elapsed = pace_.due();
  if (!elapsed || !print_) return;
  char seconds[48];
  std::snprintf(seconds, sizeof seconds, "; %.1f s so far", *elapsed);
  const std::string line = label_ + ": setting up its part: " + phase_ + seconds;
  guard.unlock();
  print_(line);
}

void SetupProgress::watch(double period_s) {
  stop_watch();
  std::lock_guard guard(mutex_);
  stopping_ = false;
  watcher_ = std::thread([this, period = std::chrono::duration<double>(period_s)] {
    std::unique_lock lock(mutex_);
    while (!wake_.wait_for(lock, period, [this] { return stopping_; })) {
      lock.unlock();
      poll();
      lock.lock();
    }
  });
}

void SetupProgress::stop_watch() {
  {
    std::lock_guard guard(mutex_);
    stopping_ = true;
  }
  wake_.notify_all();
  if (watcher_.joinable()) watcher_.join();
}

void SetupProgress::finish() {
  stop_watch();
  poll();  // the last phase, if a line is due
  std::unique_lock guard(mutex_);
  if (!pace_.spoke() || !print_) return;
  char line[64];
  std::snprintf(line, sizeof line, ": part set up in %.1f s", pace_.elapsed());
  guard.unlock();
  print_(label_ + line);
}

}  // namespace rths::runtime
