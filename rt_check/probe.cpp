#include "rt_check/probe.h"

#include <fcntl.h>
#include <sys/resource.h>
#include <unistd.h>

#include <cctype>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace rths::rt_check {
namespace {

// The file's first line without trailing white space; nullopt-like empty with ok = false.
bool read_line(const std::filesystem::path& path, std::string& line) {
  std::ifstream in(path);
  if (!in || !std::getline(in, line)) return false;
  while (!line.empty() && std::isspace(static_cast<unsigned char>(line.back()))) line.pop_back();
  return true;
}

std::string preemption_of(const std::filesystem::path& root, const std::string& version) {
  std::string realtime;
  if (read_line(root / "sys/kernel/realtime", realtime) && realtime == "1") return "PREEMPT_RT";
  if (version.find("PREEMPT_RT") != std::string::npos) return "PREEMPT_RT";
  if (version.find("PREEMPT_DYNAMIC") != std::string::npos) {
    // "none voluntary (full) lazy": the chosen mode is the one in parentheses.
    std::string modes;
    if (read_line(root / "sys/kernel/debug/sched/preempt", modes)) {
      const auto open = modes.find('('), close = modes.find(')');
      if (open != std::string::npos && close != std::string::npos && close > open)
        return "PREEMPT_DYNAMIC (" + modes.substr(open + 1, close - open - 1) + ")";
    }
    return "PREEMPT_DYNAMIC";
  }
  if (version.find(" PREEMPT ") != std::string::npos) return "PREEMPT";
  if (version.empty()) return "unknown";
  return "none or voluntary";
}

std::string governor_of(const std::filesystem::path& cpu_dir, const std::vector<int>& cpus) {
  std::string out;
  for (int cpu : cpus) {
    std::string governor;
    // Appended piece by piece: GCC 12 misreads `"cpu" + std::to_string(...)` (-Wrestrict).
    std::string cpu_name = "cpu";
    cpu_name += std::to_string(cpu);
    if (!read_line(cpu_dir / cpu_name / "cpufreq/scaling_governor", governor)) continue;
    if (!out.empty()) out += ' ';
    out += std::to_string(cpu);
    out += ':';
    out += governor;
  }
  return out.empty() ? "none (no cpufreq)" : out;
}

void count_irqs(const std::filesystem::path& irq_dir, PlatformFacts& facts) {
  std::error_code ec;
  for (const auto& entry : std::filesystem::directory_iterator(irq_dir, ec)) {
    std::string list;
    if (!entry.is_directory() || !read_line(entry.path() / "smp_affinity_list", list)) continue;
    ++facts.irqs;
    for (int cpu : parse_cpu_list(list)) ++facts.irqs_on_cpu[cpu];
  }
}

std::int64_t limit_of(int resource) {
  rlimit limit{};
  if (getrlimit(resource, &limit) != 0 || limit.rlim_cur == RLIM_INFINITY) return -1;
  return static_cast<std::int64_t>(limit.rlim_cur);
}

}  // namespace

std::string PlatformFacts::irq_affinity() const {
  std::string out;
  for (int cpu : online_cpus) {
    const auto it = irqs_on_cpu.find(cpu);
    out += (out.empty() ? "" : ", ") + std::string("cpu") + std::to_string(cpu) + ": " +
           std::to_string(it == irqs_on_cpu.end() ? 0 : it->second) + " of " +
           std::to_string(irqs) + " IRQs";
  }
  return out;
}

std::vector<int> parse_cpu_list(std::string_view list) {
  std::vector<int> cpus;
  std::string text(list);
  while (!text.empty() && std::isspace(static_cast<unsigned char>(text.back()))) text.pop_back();
  if (text.empty()) return cpus;
  std::stringstream ranges(text);
  std::string range;
  const auto bad = [&] {
    return std::invalid_argument("cpu list \"" + text + "\": expected e.g. 0-2,5");
  };
  while (std::getline(ranges, range, ',')) {
    int first = 0, last = 0;
    char dash = 0;
    std::istringstream in(range);
    if (!(in >> first)) throw bad();
    last = first;
    if (in >> dash && (dash != '-' || !(in >> last))) throw bad();
    if (first < 0 || last < first || last > 4095 || !(in >> std::ws).eof()) throw bad();
    for (int cpu = first; cpu <= last; ++cpu) cpus.push_back(cpu);
  }
  return cpus;
}

PlatformFacts read_platform_files(const std::filesystem::path& root) {
  PlatformFacts facts;
  read_line(root / "proc/version", facts.kernel);
  facts.preemption = preemption_of(root, facts.kernel);
  const std::filesystem::path cpu_dir = root / "sys/devices/system/cpu";
  std::string online;
  facts.online_cpus =
      read_line(cpu_dir / "online", online) ? parse_cpu_list(online) : std::vector<int>{0};
  facts.governor = governor_of(cpu_dir, facts.online_cpus);
  read_line(cpu_dir / "isolated", facts.isolated_cpus);
  read_line(cpu_dir / "nohz_full", facts.nohz_full_cpus);
  if (facts.nohz_full_cpus == "(null)") facts.nohz_full_cpus.clear();
  parse_cpu_list(facts.isolated_cpus);  // malformed lists are reported, not ignored
  parse_cpu_list(facts.nohz_full_cpus);
  count_irqs(root / "proc/irq", facts);
  return facts;
}

PlatformFacts read_platform() {
  PlatformFacts facts = read_platform_files("/");
  facts.memlock_limit_bytes = limit_of(RLIMIT_MEMLOCK);
  facts.rtprio_limit = limit_of(RLIMIT_RTPRIO);
  facts.dma_latency_holdable = DmaLatencyHold().held();
  return facts;
}

DmaLatencyHold::DmaLatencyHold(const std::filesystem::path& device) {
  fd_ = ::open(device.c_str(), O_WRONLY | O_CLOEXEC);
  if (fd_ < 0) {
    why_not_ = device.string() + ": " + std::strerror(errno);
    return;
  }
  const std::int32_t zero = 0;
  if (::write(fd_, &zero, sizeof zero) != static_cast<ssize_t>(sizeof zero)) {
    why_not_ = device.string() + ": writing 0 failed: " + std::strerror(errno);
    ::close(fd_);
    fd_ = -1;
  }
}

DmaLatencyHold::~DmaLatencyHold() {
  if (fd_ >= 0) ::close(fd_);
}

}  // namespace rths::rt_check
