#pragma once
// The files of distributed runs (distributed_run.h): results tables, `rths run`'s plots, the lag
// plot per case, summary.json and summary.txt. Written complete or not at all (util/atomic_file).

#include <filesystem>
#include <functional>
#include <string>

#include "analysis/distributed/distributed_run.h"

namespace rths::analysis {
// links_<case>.png and .svg, two panels sharing the time axis (ms):
//   1. network lag per link, by role: measured round trip and injected round trip;
//   2. the lag the test feels on the actuator's path, stacked: the actuator lab's network round
//      trip (measured; real time only, lockstep does not feel it) with the actuator's own lag
//      (the case's delay stages' nominal delay, plus the node's delay stages) on top, the injected
//      total, and the continuous and discrete critical delays as horizontal lines.
void write_lag_plot(const DistributedResults& results, std::size_t case_index,
                    const std::filesystem::path& png);

// Returns the results file written.
// Plots that cannot be drawn are reported to `warn`; the tables and summaries are still written.
std::filesystem::path write_distributed_outputs(
    const DistributedResults& results, const std::filesystem::path& out, bool plots,
    const std::string& format, const std::function<void(const std::string&)>& warn);

}  // namespace rths::analysis
