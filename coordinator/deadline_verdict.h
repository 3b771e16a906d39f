#pragma once
// Whether an emulator's servo loop kept its deadlines, as the run's outcome says it. The
// integrator loop's own deadlines are the one real-time verdict, runtime::deadline_verdict
// (runtime/record/realtime_verdict.h), which identify and the view apply to the record too.
//   servo_deadline_misses   overruns > tolerance x periods  ->  "completed with deadline misses:
//                           the servo loop of <node> overran ..."
// tolerance: deployment max_overrun_fraction (a fraction of periods); < 0 never judges.
// Nothing (nullopt) when the servo kept within it, or when there is nothing to judge (no servo
// periods).

#include <cstdint>
#include <optional>
#include <string>

namespace rths::coordinator {

std::optional<std::string> servo_deadline_misses(const std::string& node, std::uint64_t overruns,
                                                 std::uint64_t periods, double tolerance);

}  // namespace rths::coordinator
