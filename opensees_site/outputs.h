#pragma once
// What an OpenSees site leaves beside its record (OUT/run.rthsrec), read back through the one
// reader of records (runtime::measure_run), so it says what `rths export` says:
//   results.csv              the record as a table (results::record_table: step, time_s, floors,
//                            command / realised / force per actuator, lag per link), SI units
//   command_realised.png     commanded and realised drift per actuator (mm) against time (s)
//   force_displacement.png   measured force (kN) against realised drift (mm), per actuator
//   lag.png                  per link: measured and injected round trip (ms) against time (s)
// Every plot also as SVG. Throws std::runtime_error naming the file when it cannot write one.

#include <filesystem>

namespace rths::opensees {

void write_site_outputs(const std::filesystem::path& record, const std::filesystem::path& out,
                        bool plots);

}  // namespace rths::opensees
