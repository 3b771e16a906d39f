// ScopedCpuPin: the placement `rths launch` uses for lockstep runs.
#include "runtime/process.h"

#include <gtest/gtest.h>
#include <sched.h>

#include <thread>

namespace rths::runtime {
namespace {

cpu_set_t current_mask() {
  cpu_set_t set;
  CPU_ZERO(&set);
  sched_getaffinity(0, sizeof set, &set);
  return set;
}

TEST(ScopedCpuPinTest, PinsToTheHighestAllowedCpuAndRestoresTheMask) {
  const cpu_set_t before = current_mask();
  int highest = -1;
  for (int c = 0; c < CPU_SETSIZE; ++c) {
    if (CPU_ISSET(c, &before)) highest = c;
  }
  {
    const ScopedCpuPin pin;
    EXPECT_EQ(pin.cpu(), highest);
    const cpu_set_t pinned = current_mask();
    EXPECT_EQ(CPU_COUNT(&pinned), 1);
    EXPECT_TRUE(CPU_ISSET(highest, &pinned));
    // Threads started while pinned inherit the mask: this is how the children's DDS threads
    // end up on the same CPU.
    int thread_cpus = 0;
    std::thread([&] {
      const cpu_set_t inherited = current_mask();
      thread_cpus = CPU_COUNT(&inherited);
    }).join();
    EXPECT_EQ(thread_cpus, 1);
  }
  const cpu_set_t after = current_mask();
  EXPECT_TRUE(CPU_EQUAL(&before, &after));
}

TEST(ScopedCpuPinTest, RefusesACpuOutsideTheAllowedSetNamingIt) {
  try {
    const ScopedCpuPin pin(CPU_SETSIZE - 1);
    const cpu_set_t allowed = current_mask();
    if (!CPU_ISSET(CPU_SETSIZE - 1, &allowed)) FAIL() << "expected a refusal";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(std::to_string(CPU_SETSIZE - 1)), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace rths::runtime
