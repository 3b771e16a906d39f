// platform/probe: the kernel's facts read from a fixture tree of /proc and /sys files.
#include "rt_check/probe.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <fstream>

namespace rths::rt_check {
namespace {

namespace fs = std::filesystem;
using ::testing::ElementsAre;
using ::testing::HasSubstr;

class Tree : public ::testing::Test {
 protected:
  void SetUp() override {
    root_ = fs::temp_directory_path() /
            ("rths_probe_" + std::to_string(::getpid()) + "_" +
             ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(root_);
  }
  void TearDown() override { fs::remove_all(root_); }
  void put(const std::string& path, const std::string& text) {
    fs::create_directories((root_ / path).parent_path());
    std::ofstream(root_ / path) << text;
  }
  fs::path root_;
};

TEST(ParseCpuList, RangesAndSingles) {
  EXPECT_THAT(parse_cpu_list("0-2,5"), ElementsAre(0, 1, 2, 5));
  EXPECT_THAT(parse_cpu_list("3\n"), ElementsAre(3));
  EXPECT_TRUE(parse_cpu_list("").empty());
}

TEST(ParseCpuList, RefusesWhatIsNotAList) {
  for (const char* bad : {"a", "2-1", "0-", "1,,2", "-1", "0-2x"}) {
    EXPECT_THROW(parse_cpu_list(bad), std::invalid_argument) << bad;
  }
  try {
    parse_cpu_list("2-1");
  } catch (const std::invalid_argument& e) {
    EXPECT_THAT(e.what(), HasSubstr("\"2-1\""));
  }
}

TEST_F(Tree, AStockDynamicKernelOnAVm) {
  put("proc/version", "Linux version 6.18.44 (gcc) #1 SMP PREEMPT_DYNAMIC @0\n");
  put("sys/devices/system/cpu/online", "0-1\n");
  put("sys/devices/system/cpu/isolated", "\n");
  put("proc/irq/24/smp_affinity_list", "0-1\n");
  put("proc/irq/25/smp_affinity_list", "0\n");
  put("proc/irq/default_smp_affinity", "3\n");  // a file, not an IRQ
  const PlatformFacts facts = read_platform_files(root_);
  EXPECT_EQ(facts.preemption, "PREEMPT_DYNAMIC");
  EXPECT_FALSE(facts.realtime_kernel());
  EXPECT_EQ(facts.governor, "none (no cpufreq)");
  EXPECT_EQ(facts.isolated_cpus, "");
  EXPECT_EQ(facts.nohz_full_cpus, "");
  EXPECT_THAT(facts.online_cpus, ElementsAre(0, 1));
  EXPECT_EQ(facts.irqs, 2);
  EXPECT_EQ(facts.irq_affinity(), "cpu0: 2 of 2 IRQs, cpu1: 1 of 2 IRQs");
}

TEST_F(Tree, ATunedRealTimeMachine) {
  put("proc/version", "Linux version 6.6.0-rt #1 SMP PREEMPT_RT\n");
  put("sys/kernel/realtime", "1\n");
  put("sys/devices/system/cpu/online", "0-3\n");
  put("sys/devices/system/cpu/isolated", "2-3\n");
  put("sys/devices/system/cpu/nohz_full", "2-3\n");
  for (int cpu = 0; cpu < 4; ++cpu)
    put("sys/devices/system/cpu/cpu" + std::to_string(cpu) + "/cpufreq/scaling_governor",
        cpu < 2 ? "powersave\n" : "performance\n");
  put("proc/irq/30/smp_affinity_list", "0-1\n");
  const PlatformFacts facts = read_platform_files(root_);
  EXPECT_EQ(facts.preemption, "PREEMPT_RT");
  EXPECT_TRUE(facts.realtime_kernel());
  EXPECT_EQ(facts.governor, "0:powersave 1:powersave 2:performance 3:performance");
  EXPECT_EQ(facts.isolated_cpus, "2-3");
  EXPECT_EQ(facts.nohz_full_cpus, "2-3");
  EXPECT_EQ(facts.irq_affinity(),
            "cpu0: 1 of 1 IRQs, cpu1: 1 of 1 IRQs, cpu2: 0 of 1 IRQs, cpu3: 0 of 1 IRQs");
}

TEST_F(Tree, DynamicPreemptionNamesTheChosenMode) {
  put("proc/version", "Linux version 6.8 #1 SMP PREEMPT_DYNAMIC\n");
  put("sys/kernel/debug/sched/preempt", "none voluntary (full) lazy\n");
  put("sys/devices/system/cpu/nohz_full", "(null)\n");
  const PlatformFacts facts = read_platform_files(root_);
  EXPECT_EQ(facts.preemption, "PREEMPT_DYNAMIC (full)");
  EXPECT_EQ(facts.nohz_full_cpus, "");
}

TEST_F(Tree, OlderKernelsAndMissingFiles) {
  put("proc/version", "Linux version 5.10 #1 SMP PREEMPT Mon\n");
  EXPECT_EQ(read_platform_files(root_).preemption, "PREEMPT");
  put("proc/version", "Linux version 5.10 #1 SMP Mon\n");
  EXPECT_EQ(read_platform_files(root_).preemption, "none or voluntary");
  fs::remove(root_ / "proc/version");
  const PlatformFacts empty = read_platform_files(root_);
  EXPECT_EQ(empty.preemption, "unknown");
  EXPECT_THAT(empty.online_cpus, ElementsAre(0));
}

TEST_F(Tree, AMalformedIsolatedListIsReported) {
  put("sys/devices/system/cpu/isolated", "x-y\n");
  EXPECT_THROW(read_platform_files(root_), std::invalid_argument);
}

TEST_F(Tree, DmaLatencyHoldWritesZeroAndSaysWhyNot) {
  put("dev/cpu_dma_latency", "");
  {
    DmaLatencyHold hold(root_ / "dev/cpu_dma_latency");
    EXPECT_TRUE(hold.held());
  }
  EXPECT_EQ(fs::file_size(root_ / "dev/cpu_dma_latency"), 4u);  // one int32: 0 us
  DmaLatencyHold missing(root_ / "dev/none");
  EXPECT_FALSE(missing.held());
  EXPECT_THAT(missing.why_not(), HasSubstr("dev/none"));
}

}  // namespace
}  // namespace rths::rt_check
