#pragma once
// The platform check of one deployment, as `rths rt-check`, `rths launch` and the coordinator run
// it, and its one summary (runtime::PlatformSummary: what a real-time run's record header keeps),
// as text and JSON.
//
//   check_platform   reads the facts (probe.h), measures `seconds` of wake-ups at the study's
//                    rate on the CPUs the deployment uses (latency.h: this process's CPUs plus the
//                    loop's CPU when pinned) and judges the deployment (verdict.h).
//   summary JSON     the PlatformSummary in Protobuf's JSON mapping (field names as in the proto;
//                    64-bit integers as strings), so `--platform FILE` reads back what
//                    `rths rt-check --json` printed (its "platform" object).
// Units: the summary's times in s (ms where the name says so).

#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "rt_check/verdict.h"
#include "rths/proto/runtime.pb.h"
#include "study/study.h"

namespace rths::rt_check {

struct PlatformCheck {
  PlatformFacts facts;
  FailSafeInput input;
  FailSafeVerdict verdict;
  runtime::PlatformSummary summary;
};

// The CPUs this process may run on now.
std::vector<int> allowed_cpus();

// dt and run length from the study (integrator dt, motion length). Throws std::runtime_error
// naming the CPU when a measuring thread cannot be placed.
PlatformCheck check_platform(const study::PreparedStudy& prepared, double seconds);
// The same for a deployment at dt (s) judged for a run of run_seconds.
PlatformCheck check_platform(const config::Deployment& deployment, double dt, double run_seconds,
                             double seconds);

runtime::PlatformSummary make_summary(const PlatformFacts& facts, const LatencyStats& stats,
                                      const WakeupSamples& samples, const FailSafeInput& input,
                                      const FailSafeVerdict& verdict);

std::string summary_text(const runtime::PlatformSummary& summary);
nlohmann::json summary_json(const runtime::PlatformSummary& summary);
// Throws std::invalid_argument naming the field when the JSON is not a PlatformSummary.
runtime::PlatformSummary summary_from_json(const nlohmann::json& json);
// `rths rt-check --json`'s output, or a bare summary object; throws naming the file.
runtime::PlatformSummary read_summary_file(const std::filesystem::path& path);

}  // namespace rths::rt_check
