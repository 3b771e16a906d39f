#pragma once
// Whether a real-time run kept its deadlines, as its outcome says it.
//   loop_deadline_misses    overruns > tolerance x steps  ->  "completed with deadline misses: N
//                           overruns in S steps (P %, tolerance T %; worst streak W)"
//   servo_deadline_misses   an emulator's servo loop: overruns > tolerance x periods  ->
//                           "completed with deadline misses: the servo loop of <node> overran ..."
// tolerance: deployment max_overrun_fraction (a fraction of steps or periods); < 0 never judges.
// Nothing (nullopt) when the run kept within it, or when there is nothing to judge (no steps, no
// servo periods).

#include <cstdint>
#include <optional>
#include <string>

namespace rths::coordinator {

std::optional<std::string> loop_deadline_misses(std::uint64_t overruns, std::uint64_t worst_streak,
                                                std::uint64_t steps, double tolerance);
std::optional<std::string> servo_deadline_misses(const std::string& node, std::uint64_t overruns,
                                                 std::uint64_t periods, double tolerance);

}  // namespace rths::coordinator
