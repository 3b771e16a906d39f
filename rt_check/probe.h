#pragma once
// What the machine offers a real-time loop, read from /proc and /sys under `root` (so tests read
// fixture trees) and from the process's own limits. Nothing here measures time (latency.h does).
//
//   preemption    /sys/kernel/realtime = 1 -> "PREEMPT_RT"; else /proc/version's "PREEMPT_RT",
//                 "PREEMPT_DYNAMIC" (followed by the mode /sys/kernel/debug/sched/preempt marks
//                 in parentheses, when readable), "PREEMPT"; else "none or voluntary".
//   governor      /sys/devices/system/cpu/cpuN/cpufreq/scaling_governor for each online CPU, as
//                 "0:performance 1:powersave"; "none (no cpufreq)" when no CPU has one (a VM).
//   isolated, nohz_full   /sys/devices/system/cpu/{isolated,nohz_full}: kernel cpu lists.
//   irqs_on_cpu   for each online CPU, how many of /proc/irq/N/smp_affinity_list include it.
//   limits        RLIMIT_MEMLOCK (bytes) and RLIMIT_RTPRIO; -1 = unlimited.
//   dma latency   whether /dev/cpu_dma_latency opens for writing and takes 0 (DmaLatencyHold).

#include <cstdint>
#include <filesystem>
#include <map>
#include <string>
#include <string_view>
#include <vector>

namespace rths::rt_check {

struct PlatformFacts {
  std::string kernel;  // /proc/version's first line
  std::string preemption;
  std::string governor;
  std::string isolated_cpus, nohz_full_cpus;  // kernel cpu lists, "" = none
  std::vector<int> online_cpus;
  std::map<int, int> irqs_on_cpu;  // cpu -> IRQs whose affinity includes it
  int irqs = 0;                    // IRQs read
  std::int64_t memlock_limit_bytes = -1, rtprio_limit = -1;
  bool dma_latency_holdable = false;
  bool realtime_kernel() const { return preemption == "PREEMPT_RT"; }
  std::string irq_affinity() const;  // "cpu0: 19 of 19 IRQs, cpu1: 19 of 19 IRQs"
};

// "0-2,5" -> {0, 1, 2, 5}; "" -> {}. Throws std::invalid_argument naming the list.
std::vector<int> parse_cpu_list(std::string_view list);

// The kernel's files under root (root "/" reads this machine). Missing files leave their field
// at "unknown", "none" or empty; a malformed cpu list throws std::invalid_argument naming it.
PlatformFacts read_platform_files(const std::filesystem::path& root);

// read_platform_files("/") plus this process's limits and whether /dev/cpu_dma_latency is holdable.
PlatformFacts read_platform();

// Holds /dev/cpu_dma_latency at 0 us while it lives (the kernel keeps CPUs out of deep idle
// states while the file is open with 0 written), as cyclictest and tuned's latency profiles do.
class DmaLatencyHold {
 public:
  explicit DmaLatencyHold(const std::filesystem::path& device = "/dev/cpu_dma_latency");
  ~DmaLatencyHold();
  DmaLatencyHold(const DmaLatencyHold&) = delete;
  DmaLatencyHold& operator=(const DmaLatencyHold&) = delete;
  bool held() const { return fd_ >= 0; }
  const std::string& why_not() const { return why_not_; }  // when not held

 private:
  int fd_ = -1;
  std::string why_not_;
};

}  // namespace rths::rt_check
