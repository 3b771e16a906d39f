#pragma once
// Fuzz entry points: each feeds arbitrary bytes to one of rths's parsers of outside input and
// returns 0. Input the parser rejects must end in its documented error -- std::invalid_argument
// or std::runtime_error, caught here; anything else (a crash, an AddressSanitizer or UBSan report,
// any other exception, a hang, a leak) is a bug the fuzzer reports.
//
//   study_config       study::parse_study + validate_study, then the hybrid setup of the reference
//                      case without its motion (structure, partition, delay chains)
//   study_values       study::parse_study (with its validation): a refusal must name a field of the
//                      study or a line:column; an accepted study must hold no value that is not
//                      finite, and no given value that must be > 0 (Sdof.mass, the benchmark
//                      plant's mass and stiffness) that is not: a default stands only for an
//                      omitted value (study_values.cpp; a violation throws std::logic_error)
//   deployment_config  a config::Deployment in text format, its default nodes and plan against
//                      the paper's frame (runtime::with_default_nodes, make_plan)
//   sites_config       deploy::parse_sites (the `rths sites` config)
//   at2_motion         study::read_at2 (PEER AT2, both header dialects)
//   column_motion      study::read_columns, one column at dt = 0.01 s and two columns (dt = 0)
//   daq_export         identify::read_measured (DAQ raw export or CSV), at least 2 samples
//   run_record         runtime::read_record, then the CSV table `rths export` writes of it
//   record_flips       a checksummed record built from the input, with bytes flipped as the
//                      input says, read back (runtime::parse_record): every damaged entry must be
//                      dropped and reported in a loss region, every intact one recovered as it
//                      was (check_flipped_record; a violation throws std::logic_error, which the
//                      fuzzer reports). Input: [steps: uint16 LE, 1 + value % 1024], then records
//                      of [position: uint32 LE, modulo the record's size][xor: 1 byte, 0 -> 0x01].
//   envelope_payload   DDS envelopes as they arrive at the two node services (substructure node,
//                      actuator emulator): runtime::check_envelope and NodeService::handle.
//                      Input: byte 0 flags (bit 0: both nodes are first assigned the paper's frame;
//                      bit 1: messages carry another run's id), then records of
//                      [kind: 1 byte][step: int32 LE][payload size: uint16 LE][payload bytes].
//   controller_frame   a controller's UDP frame layout and a frame (controller_node/frame.h):
//                      check_frame_layout, decode, and for a frame that decodes, encode and decode
//                      again, which must give the same values (a difference throws
//                      std::logic_error, which the fuzzer reports). Input: byte 0 = field count
//                      (1 + value % 16) | bit 7: feedback (else command), then 2 bytes per field
//                      [role % 9][type: bits 0-1, big endian: bit 2, actuator: bit 3 of 2],
//                      every scale 1; the rest is the frame.
//
// File-based readers get the bytes through one scratch file per process (FuzzScratch).
// libfuzzer_main.cpp wraps one entry as LLVMFuzzerTestOneInput; tests/fuzz runs every entry over
// its seed corpus (fuzz/corpus/<name>/) with the normal compiler, so the harness cannot rot.

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "rths/proto/runtime.pb.h"

namespace rths::fuzz {

using Entry = int (*)(const std::uint8_t* data, std::size_t size);

struct Target {
  const char* name;  // also the corpus folder and the libFuzzer program suffix
  Entry entry;
};

int study_config(const std::uint8_t* data, std::size_t size);
int study_values(const std::uint8_t* data, std::size_t size);
int deployment_config(const std::uint8_t* data, std::size_t size);
int sites_config(const std::uint8_t* data, std::size_t size);
int at2_motion(const std::uint8_t* data, std::size_t size);
int column_motion(const std::uint8_t* data, std::size_t size);
int daq_export(const std::uint8_t* data, std::size_t size);
int run_record(const std::uint8_t* data, std::size_t size);
int record_flips(const std::uint8_t* data, std::size_t size);
int envelope_payload(const std::uint8_t* data, std::size_t size);
int controller_frame(const std::uint8_t* data, std::size_t size);

const std::vector<Target>& targets();

// The paper's frame (lag_shift_14ms case) assigned to node `node_id` of `kind`, dt = 1 ms: what
// flag bit 0 of envelope_payload delivers first.
runtime::Assign paper_assign(int node_id, config::NodeSpec::Kind kind);

// A checksummed record of a short real-time run: header, `steps` steps (a sine, two links), an
// event every 100 steps, and a footer.
std::string flip_test_record(int steps);

// What a reader made of a record with bytes flipped (`damaged`, the same size as `original`):
// per entry of the original, damaged (a byte of its frame differs) or intact.
struct FlipVerdict {
  std::size_t entries = 0, damaged = 0, intact = 0;
  std::size_t detected = 0;     // damaged, dropped, and inside a reported loss region
  std::size_t recovered = 0;    // intact and read back byte for byte
  std::size_t silent = 0;       // damaged but read back as an entry, or an entry that never was
  std::size_t unreported = 0;   // damaged, dropped, but in no loss region
  std::size_t lost_intact = 0;  // intact but not read back
  bool holds() const { return silent == 0 && unreported == 0 && lost_intact == 0; }
  FlipVerdict& operator+=(const FlipVerdict& other);
};
FlipVerdict check_flipped_record(const std::string& original, const std::string& damaged);

// The record_flips input for a record of `steps` steps with these (position, xor) flips.
std::string flips_input(int steps,
                        const std::vector<std::pair<std::uint32_t, std::uint8_t>>& flips);

// One envelope record in the envelope_payload input format.
std::string envelope_record(std::int32_t kind, std::int32_t step, const std::string& payload);

}  // namespace rths::fuzz
