// blind_record: what every blind record writer shares (docs/development.md, "Blind records"),
// written from docs/records.md ("Format") and proto/runtime.proto (RecordEntry) alone, nothing of
// rths's own: the CRC-32C and framing, the El Centro motion read from data/, the paper's frame
// as the study that was run, the run record itself and its truth.json.
//
// Units: SI (m, s, N); the motion in m/s^2 at the run's dt.
// The record (format version 2): "RTHSREC\x02", the header frame, the inputs frame, the header
// again before every 1000th step, one step frame per sample, the header, the footer frame.

#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "rths/proto/runtime.pb.h"

namespace blind {

// CRC-32C (Castagnoli, reflected polynomial 0x82F63B78, init and final xor ~0) of bytes.
std::uint32_t crc32c(const std::string& bytes);

// One frame per docs/records.md: sync F3 7A 1C B5 | size u32 | crc32c(payload) u32 |
// crc32c(the 12 bytes before) u32 | payload, little-endian.
std::string frame(const std::string& payload);

// The entry's bytes; throws std::runtime_error when it cannot be serialised.
std::string serialise(const rths::runtime::RecordEntry& entry);

struct Motion {
  std::string name;           // file stem
  std::string path;           // absolute
  std::string file_sha256;    // from data/SHA256SUMS
  std::vector<double> accel;  // m/s^2 at the run's dt
};

// The AT2 file `file` of data_dir/ground_motions (four header lines, one holding "DT= s"; values
// in g; by default the 1979 El Centro record) linearly interpolated to dt for `steps` samples,
// with its checksum from data_dir/SHA256SUMS. Throws std::runtime_error naming the file when it
// cannot be read, is shorter than the run or has no checksum.
Motion read_motion(const std::filesystem::path& data_dir, double dt, int steps,
                   const std::string& file = "RSN175_IMPVALL.H_H-E12140.AT2");

// The state of one record step at t_k = k dt: the integrator's u_k (m), v_k (m/s), a_k (m/s^2),
// the command u_k (m), the realised (measured) displacement y_k (m) and the load cell's F_k (N).
struct RecordedStep {
  double u = 0.0;
  double v = 0.0;
  double a = 0.0;
  double command = 0.0;
  double realised = 0.0;
  double force = 0.0;
};

// A lockstep run of the paper's frame declaring a 14 ms shift (case "lag_shift_14ms"), or of the
// study write_run_record is given, over a substructure node (1) and an actuator emulator (2). The seed sets the run's start time and the
// link timings' jitter (seconds, plausible for loopback), never the physics.
struct RunToRecord {
  std::string run_id;
  std::uint64_t seed = 0;
  double dt = 0.001;       // s
  double duration = 15.0;  // s, as the study's motion states it
  const Motion* motion = nullptr;
  std::vector<RecordedStep> steps;  // one per motion sample, step 0 the rest
};

// Writes the run as a record at path; throws std::runtime_error when it cannot.
void write_run_record(const std::filesystem::path& path, const RunToRecord& run);

// The study a run of another rig declares: its one-DOF, one-actuator study (text format, a
// lockstep deployment over nodes 1 and 2 whose case_name is case_name); dt, motion and run id are
// the run's.
struct DeclaredStudy {
  std::string study_text;
  std::string case_name;
};

// As above, the run declaring `declared` instead of the paper's frame; throws
// std::runtime_error when the study does not parse or its deployment runs another case.
void write_run_record(const std::filesystem::path& path, const RunToRecord& run,
                      const DeclaredStudy& declared);

// A writer's command line: --set S --out DIR --data DIR [--duration S] [--case NAME] (only:
// one case by name, empty for every case). Checking the values is the writer's.
struct WriterArgs {
  std::string set;
  std::string out_dir;
  std::string data_dir;
  std::string only;
  double duration = 15.0;  // s
};

// The writer's command line (program: its name in messages; sets: the sets it writes), or
// nullopt after saying on stderr what is wrong: an unknown argument, one without its value, or
// (with the usage) a set it does not write, no --out or --data, a duration outside (1, 39] s.
std::optional<WriterArgs> writer_args(int argc, char** argv, const std::string& program,
                                      const std::vector<std::string>& sets);

struct TruthCase;

// Writes a set's cases into args.out_dir (created), each by write_case(i) (its truth), or only
// the one named args.only, printing each record's path and what it holds, then truth.json;
// throws std::runtime_error when the set has no case named args.only.
void write_set(const WriterArgs& args, const std::vector<std::string>& names,
               const std::function<TruthCase(std::size_t)>& write_case);

// One case of truth.json (tests/blind/score_blind.py reads it): part (empty: none), description
// kinds, frequency (Hz; <= 0: none), the library effects in the rig and the names that describe
// the effect itself, each (part, effect); window_s: when an event-like effect happens (s).
struct TruthCase {
  std::string name;
  std::string set;
  std::uint64_t seed = 0;
  std::string what;
  std::string part;
  std::vector<std::string> kinds;
  double frequency_hz = 0.0;
  std::vector<std::pair<std::string, std::string>> library;
  std::vector<std::pair<std::string, std::string>> accepted;
  std::optional<std::pair<double, double>> window_s;
};

// Writes {"duration_s": ..., "cases": [...]} with each case's record <name>.rthsrec; throws
// std::runtime_error when it cannot.
void write_truth(const std::filesystem::path& path, const std::vector<TruthCase>& cases,
                 double duration);

}  // namespace blind
