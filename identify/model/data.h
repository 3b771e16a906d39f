#pragma once
// Measured lab records: loading, checking and splitting.
//
// Output (MeasuredData), SI units: time (s, uniform step dt), command and measured displacement
// (m), measured force (N). Two input formats:
//   CSV   header `time,command,measured,force` (any column order, extra columns ignored); the
//         file's units are given by CsvUnits (default s, mm, mm, N).
//   DAQ   a raw export as written by the MTS/NI logger: `Header Size: H` on the first line, H
//         header lines, the last of which names the columns (`Sample Number, Date/Time,
//         CHANNEL0, ...`), then one sample per line. Time is (sample number - first) * the
//         header's `Sampling Interval`. A DaqColumnMap names the channel and scale factor for
//         each signal: value_in_mm_or_N = raw * scale.
// Time without a time column: `sample_rate` (Hz, the CLI's --sample-rate; 0 = not given) makes
// time = sample index / sample_rate for a CSV without a `time` column and sets the interval of a
// DAQ export whose header gives neither `Sampling Interval` nor `Sampling Rate`; a DAQ export
// without a `Sample Number` column is then timed by its row index. A file with neither a time
// base nor a given rate is refused, naming --sample-rate; a given rate that disagrees (> 1 %) with
// the file's own time base is refused too.
// The force column: ForceColumn::kOptional (the actuator channel alone is identified) reads it
// when the file has it and leaves `force` empty when it has not; kRequired refuses a file without.
// Every loader throws std::invalid_argument naming the file, line and column when a column is
// missing, a value is not a number or is NaN/inf, time does not increase, or there are fewer than
// `min_samples` samples.

#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

namespace rths::identify {

struct MeasuredData {
  std::string source;            // file name, for messages
  double dt = 0.0;               // s
  std::vector<double> time;      // s
  std::vector<double> command;   // m
  std::vector<double> measured;  // m
  std::vector<double> force;     // N; empty when the file has no force column (ForceColumn)
  std::size_t size() const { return time.size(); }
  bool has_force() const { return !force.empty(); }
};

struct CsvUnits {
  double time_to_s = 1.0;
  double length_to_m = 1.0e-3;  // file in mm
  double force_to_n = 1.0;
};

// Conversion factor for a unit name: s, ms (time); m, mm, cm, in (length); N, kN, lbf, kip (force).
// Throws std::invalid_argument naming the unit.
double time_unit_to_s(const std::string& unit);
double length_unit_to_m(const std::string& unit);
double force_unit_to_n(const std::string& unit);

struct ChannelSource {
  std::string column;  // header name in the file, e.g. CHANNEL2
  double scale = 1.0;  // raw -> mm (displacements) or N (force)
};

struct DaqColumnMap {
  ChannelSource command{"CHANNEL2", 10.0};
  ChannelSource measured{"CHANNEL0", 10.0};
  ChannelSource force{"CHANNEL1", 9806.65};
};

// Parses "command=CHANNEL2*10,measured=CHANNEL0*10,force=CHANNEL1*9806.65" (any order; a
// missing signal keeps its default). Throws std::invalid_argument naming the bad entry.
DaqColumnMap parse_column_map(const std::string& text);

inline constexpr std::size_t kDefaultMinSamples = 200;

enum class ForceColumn { kRequired, kOptional };

MeasuredData read_csv(const std::filesystem::path& path, const CsvUnits& units = {},
                      std::size_t min_samples = kDefaultMinSamples, double sample_rate = 0.0,
                      ForceColumn force = ForceColumn::kRequired);
MeasuredData read_daq(const std::filesystem::path& path, const DaqColumnMap& map = {},
                      std::size_t min_samples = kDefaultMinSamples, double sample_rate = 0.0,
                      ForceColumn force = ForceColumn::kRequired);
// DAQ when the first line starts with "Header Size", CSV otherwise.
MeasuredData read_measured(const std::filesystem::path& path, const CsvUnits& units = {},
                           const DaqColumnMap& map = {},
                           std::size_t min_samples = kDefaultMinSamples, double sample_rate = 0.0,
                           ForceColumn force = ForceColumn::kRequired);

// Writes the CSV format above (s, mm, mm, N; without the force column when the record has none).
// Throws std::runtime_error naming the file.
void write_csv(const MeasuredData& data, const std::filesystem::path& path);

// Checks sizes (force: as long as time, or empty), finiteness, strictly increasing and uniform
// (within 1 %) time, and length. Sets dt to the mean step. Throws std::invalid_argument naming the
// source and the sample.
void validate(MeasuredData& data, std::size_t min_samples);

// Samples [begin, end) as a record of their own (time kept). Throws std::invalid_argument when
// the range is empty or beyond the record.
MeasuredData slice(const MeasuredData& data, std::size_t begin, std::size_t end);

// The active part of a record, [begin, end): lab records start seconds before the test and run on
// after it, and those idle stretches hold only sensor noise (which a hysteretic specimen model fed
// a noisy displacement turns into spurious force, and which weighs on whichever fold holds it).
// The command's rest values are its means over the first and the last `rest_window` seconds;
// begin is the first sample whose command leaves the first rest value by more than
// `threshold` x the command's largest such deviation, less `margin` seconds (so the model starts
// at rest); end likewise from the last rest value, plus `margin`. A record that moves from its
// first to its last sample is returned whole. @pre threshold in (0, 1), margin >= 0.
struct ActiveRange {
  std::size_t begin = 0, end = 0;
};
ActiveRange active_range(const MeasuredData& data, double threshold = 0.05, double margin = 0.25,
                         double rest_window = 0.5);

// Every `factor`-th sample (factor >= 1), after a centred moving average over `factor` samples
// so that decimation does not alias the noise.
MeasuredData decimated(const MeasuredData& data, std::size_t factor);

// Which samples train the model and which are held out from the fit to judge it.
//   kLast     the last `holdout_fraction` of the record (extrapolation in time).
//   kBlocks   the record cut into `blocks` contiguous segments; a spread-out share
//             `holdout_fraction` of them is held out (segment-wise validation: a chirp's held-out
//             data then covers its whole frequency range). The last block is always held out.
// The model always runs over the whole record; only the residuals are split.
enum class HoldoutMode { kLast, kBlocks };
HoldoutMode parse_holdout_mode(const std::string& name);  // "last" or "blocks"

struct Split {
  std::vector<std::size_t> train, heldout;  // sample indices, increasing
  std::size_t size = 0;
};
// @pre 0 < holdout_fraction < 1. Throws std::invalid_argument otherwise or when either part
// would have fewer than `min_part` samples.
Split holdout_split(std::size_t samples, double holdout_fraction,
                    HoldoutMode mode = HoldoutMode::kLast, std::size_t blocks = 10,
                    std::size_t min_part = 50);

}  // namespace rths::identify
