#pragma once
// The figures of a distributed run's identification (`rths identify RECORD.rthsrec --out DIR`),
// through util/plot (PNG with an SVG beside each):
//   record_lag.png       per link, over the run: the measured round trip, the lag the node
//                        injected and the identified model of the round trip (ms); none for a
//                        record without links (a lab's record made by another controller);
//   record_response.png  per floor: the recorded displacement and the re-runs with the declared
//                        and the identified models (mm), and below it the two errors (mm);
//   record_shares.png    the NRMSE of the worst floor each actuator link, the platform's late
//                        answers and each undeclared effect remove (%), one bar each (with the
//                        residual).
// Throws std::runtime_error naming the file when gnuplot fails.

#include <filesystem>
#include <string>
#include <vector>

#include "identify/run/run_record.h"

namespace rths::identify {

// Returns the PNG paths written.
std::vector<std::filesystem::path> write_run_plots(const RunIdentification& run,
                                                   const std::filesystem::path& dir);

}  // namespace rths::identify
