#include "runtime/rt/fifo.h"

#include <gtest/gtest.h>
#include <pthread.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <condition_variable>
#include <mutex>
#include <string>
#include <thread>

namespace rths::runtime {
namespace {

int this_tid() { return static_cast<int>(syscall(SYS_gettid)); }

// A thread named `name` that waits until told to end; its id is known once it runs.
class NamedThread {
 public:
  explicit NamedThread(const std::string& name) {
    thread_ = std::thread([this, name] {
      pthread_setname_np(pthread_self(), name.c_str());
      std::unique_lock lock(mutex_);
      tid_ = this_tid();
      changed_.notify_all();
      changed_.wait(lock, [this] { return done_; });
    });
    std::unique_lock lock(mutex_);
    changed_.wait(lock, [this] { return tid_ != 0; });
  }
  ~NamedThread() {
    {
      std::lock_guard lock(mutex_);
      done_ = true;
    }
    changed_.notify_all();
    thread_.join();
  }
  int tid() const { return tid_; }

 private:
  std::mutex mutex_;
  std::condition_variable changed_;
  int tid_ = 0;
  bool done_ = false;
  std::thread thread_;
};

// Runs `body` on a thread of its own, so the test's thread is never left on SCHED_FIFO.
template <typename Body>
void on_own_thread(Body body) {
  std::thread(body).join();
}

TEST(Fifo, RaisesTheLoopAndTheNamedThreadsForItsLifeAndPutsThemBack) {
  NamedThread receiver("rths-fifo-recv");
  NamedThread bystander("rths-fifo-other");
  on_own_thread([&] {
    std::string result;
    {
      const FifoThreads fifo(7, "probe-loop", {"rths-fifo-recv", "absent"});
      result = fifo.summary();
      EXPECT_EQ(fifo.raised(), result.find("refused") == std::string::npos);
      if (fifo.raised()) {
        EXPECT_EQ(result, "SCHED_FIFO 7: probe-loop, rths-fifo-recv");
        EXPECT_EQ(scheduling_class(), "FF");
        EXPECT_EQ(scheduling_class(receiver.tid()), "FF");
        EXPECT_EQ(scheduling_class(bystander.tid()), "TS");
      }
    }
    // Once it is gone, every thread is as it was.
    EXPECT_EQ(scheduling_class(), "TS");
    EXPECT_EQ(scheduling_class(receiver.tid()), "TS");
    EXPECT_EQ(scheduling_class(bystander.tid()), "TS");
    if (result.rfind("SCHED_FIFO 7 refused (", 0) == 0) {
      // Without the privilege (CAP_SYS_NICE or RLIMIT_RTPRIO): named, and nothing half raised.
      EXPECT_NE(result.find("probe-loop"), std::string::npos) << result;
      EXPECT_NE(result.find("the threads run unprioritised"), std::string::npos) << result;
    }
  });
}

TEST(Fifo, AThreadTheLoopStartsAfterwardsInheritsItsPriority) {
  std::string refused, child_class;
  on_own_thread([&] {
    const FifoThreads fifo(5, "loop", {});
    if (!fifo.raised()) {
      refused = fifo.summary();
      return;
    }
    std::thread([&] { child_class = scheduling_class(); }).join();
  });
  if (!refused.empty()) GTEST_SKIP() << refused;
  EXPECT_EQ(child_class, "FF");
}

TEST(Fifo, APriorityOutsideTheKernelsRangeIsRefusedNamingIt) {
  on_own_thread([] {
    const FifoThreads fifo(0, "loop", {});
    EXPECT_FALSE(fifo.raised());
    EXPECT_EQ(
        fifo.summary(),
        "SCHED_FIFO 0 refused (priority 0 is outside 1 to 99); the threads run unprioritised");
    EXPECT_EQ(scheduling_class(), "TS");
  });
}

}  // namespace
}  // namespace rths::runtime
