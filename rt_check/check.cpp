#include "rt_check/check.h"

#include <google/protobuf/util/json_util.h>
#include <sched.h>
#include <unistd.h>

#include <fstream>
#include <sstream>
#include <stdexcept>

namespace rths::rt_check {
namespace {

std::string cpu_list(const std::vector<int>& cpus) {
  std::string out;
  // Appended piece by piece: GCC 12 misreads `"," + std::to_string(...)` here (-Wrestrict).
  for (int cpu : cpus) {
    if (!out.empty()) out += ',';
    out += std::to_string(cpu);
  }
  return out;
}

std::string host_name() {
  char name[256] = {};
  return gethostname(name, sizeof name - 1) == 0 ? name : "unknown";
}

}  // namespace

std::vector<int> allowed_cpus() {
  cpu_set_t set;
  CPU_ZERO(&set);
  std::vector<int> cpus;
  if (sched_getaffinity(0, sizeof set, &set) != 0) return {0};
  for (int cpu = 0; cpu < CPU_SETSIZE; ++cpu)
    if (CPU_ISSET(cpu, &set)) cpus.push_back(cpu);
  return cpus;
}

PlatformCheck check_platform(const study::PreparedStudy& prepared, double seconds) {
  const double dt = prepared.base.dt;
  return check_platform(prepared.config.deployment(), dt,
                        static_cast<double>(prepared.motion.acceleration.size()) * dt, seconds);
}

PlatformCheck check_platform(const config::Deployment& deployment, double dt, double run_seconds,
                             double seconds) {
  PlatformCheck check;
  check.facts = read_platform();
  check.input = failsafe_input(deployment, dt, run_seconds, allowed_cpus());
  const WakeupSamples samples = measure_wakeups(check.input.cpus, 1.0 / dt, seconds);
  const LatencyStats stats(samples);
  check.verdict = judge_failsafe(stats, check.facts, check.input);
  check.summary = make_summary(check.facts, stats, samples, check.input, check.verdict);
  return check;
}

runtime::PlatformSummary make_summary(const PlatformFacts& facts, const LatencyStats& stats,
                                      const WakeupSamples& samples, const FailSafeInput& input,
                                      const FailSafeVerdict& verdict) {
  runtime::PlatformSummary s;
  s.set_host(host_name());
  s.set_kernel(facts.kernel);
  s.set_preemption(facts.preemption);
  s.set_governor(facts.governor);
  s.set_isolated_cpus(facts.isolated_cpus);
  s.set_nohz_full_cpus(facts.nohz_full_cpus);
  s.set_irq_affinity(facts.irq_affinity());
  s.set_memlock_limit_bytes(facts.memlock_limit_bytes);
  s.set_rtprio_limit(facts.rtprio_limit);
  s.set_dma_latency_holdable(facts.dma_latency_holdable);
  s.set_measured_cpus(cpu_list(samples.cpus));
  s.set_rate_hz(samples.rate_hz);
  s.set_measured_seconds(samples.seconds);
  s.set_wakeups(stats.wakeups());
  s.set_lateness_median(stats.quantile(0.5));
  s.set_lateness_p99(stats.quantile(0.99));
  s.set_lateness_p9999(stats.quantile(0.9999));
  s.set_lateness_max(stats.max());
  s.set_stalls_over_1ms_per_minute(stats.stalls_per_minute(1e-3));
  s.set_stalls_over_2ms_per_minute(stats.stalls_per_minute(2e-3));
  s.set_stalls_over_5ms_per_minute(stats.stalls_per_minute(5e-3));
  s.set_run_seconds(input.run_seconds);
  s.set_window_ms(verdict.window_ms);
  s.set_required_window_ms(verdict.required_window_ms);
  s.set_predicted_overrun_fraction(verdict.predicted_overrun_fraction);
  s.set_refused(verdict.refused());
  s.set_verdict(verdict.refusal());
  return s;
}

std::string summary_text(const runtime::PlatformSummary& s) {
  std::ostringstream out;
  const auto limit = [](std::int64_t v) {
    return v < 0 ? std::string("unlimited") : std::to_string(v);
  };
  out << "host " << s.host() << ": " << s.kernel() << "\n"
      << "preemption: " << s.preemption() << "; governor: " << s.governor()
      << "\nisolated CPUs: " << (s.isolated_cpus().empty() ? "none" : s.isolated_cpus())
      << "; nohz_full: " << (s.nohz_full_cpus().empty() ? "none" : s.nohz_full_cpus())
      << "\nIRQ affinity: " << s.irq_affinity() << "\nlimits: memlock "
      << limit(s.memlock_limit_bytes()) << " bytes, rtprio " << limit(s.rtprio_limit())
      << "; /dev/cpu_dma_latency " << (s.dma_latency_holdable() ? "can be held" : "cannot be held")
      << "\nwake-up lateness at " << s.rate_hz() << " Hz, " << s.measured_seconds() << " s on CPUs "
      << s.measured_cpus() << " (" << s.wakeups() << " wake-ups): median "
      << 1e6 * s.lateness_median() << " us, p99 " << 1e6 * s.lateness_p99() << " us, p99.99 "
      << 1e6 * s.lateness_p9999() << " us, max " << 1e6 * s.lateness_max() << " us"
      << "\nstalls per minute (all CPUs): > 1 ms " << s.stalls_over_1ms_per_minute() << ", > 2 ms "
      << s.stalls_over_2ms_per_minute() << ", > 5 ms " << s.stalls_over_5ms_per_minute() << "\n"
      << s.verdict();
  if (s.accepted_override()) out << "refused, run anyway (--accept-platform)\n";
  return out.str();
}

nlohmann::json summary_json(const runtime::PlatformSummary& summary) {
  std::string text;
  google::protobuf::util::JsonPrintOptions options;
  options.preserve_proto_field_names = true;
  options.always_print_primitive_fields = true;
  if (!google::protobuf::util::MessageToJsonString(summary, &text, options).ok())
    throw std::runtime_error("platform summary: cannot write JSON");
  return nlohmann::json::parse(text);
}

runtime::PlatformSummary summary_from_json(const nlohmann::json& json) {
  runtime::PlatformSummary summary;
  const auto status = google::protobuf::util::JsonStringToMessage(json.dump(), &summary);
  if (!status.ok())
    throw std::invalid_argument("platform summary: " + std::string(status.message()));
  return summary;
}

runtime::PlatformSummary read_summary_file(const std::filesystem::path& path) {
  std::ifstream in(path);
  if (!in) throw std::invalid_argument("platform file " + path.string() + ": cannot be read");
  nlohmann::json json = nlohmann::json::parse(in, nullptr, false);
  if (json.is_discarded() || !json.is_object())
    throw std::invalid_argument("platform file " + path.string() + ": not a JSON object");
  try {
    return summary_from_json(json.contains("platform") ? json["platform"] : json);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(path.string() + ": " + e.what());
  }
}

}  // namespace rths::rt_check
