// rths_fuzz_seed_envelope DIR: writes the envelope_payload seeds (fuzz/corpus/envelope_payload/):
// the message sequences of a short lockstep run of the paper's frame as the two nodes receive
// them. Run once when runtime.proto changes; the seeds are committed.
#include <filesystem>
#include <fstream>
#include <iostream>

#include "fuzz/targets.h"
#include "runtime/node/schema.h"

namespace {

using namespace rths;

std::string command(double time, double drift, double velocity) {
  runtime::Command c;
  c.set_time(time);
  c.add_drift(drift);
  c.add_drift_velocity(velocity);
  return c.SerializeAsString();
}

void write(const std::filesystem::path& file, const std::string& bytes) {
  std::ofstream(file, std::ios::binary) << bytes;
  std::cout << file.string() << " (" << bytes.size() << " bytes)\n";
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::cerr << "usage: rths_fuzz_seed_envelope DIR\n";
    return 2;
  }
  const std::filesystem::path dir = argv[1];
  std::filesystem::create_directories(dir);
  // Assigned nodes: commands of steps 1..8, a duplicate, a stale one, a HOLD and a STOP.
  std::string run(1, '\x01');
  for (int k = 1; k <= 8; ++k)
    run += fuzz::envelope_record(runtime::COMMAND, k, command(k * 0.001, 1e-4 * k, 0.1));
  run += fuzz::envelope_record(runtime::COMMAND, 8, command(0.008, 8e-4, 0.1));
  run += fuzz::envelope_record(runtime::COMMAND, 3, command(0.003, 3e-4, 0.1));
  runtime::Hold hold;
  hold.set_reason("fuzz seed");
  run += fuzz::envelope_record(runtime::HOLD, 9, hold.SerializeAsString());
  run += fuzz::envelope_record(runtime::STOP, 9, runtime::Stop().SerializeAsString());
  write(dir / "assigned_run", run);
  // Unassigned nodes: every kind with an empty payload, then commands with a wrong storey count.
  std::string kinds(1, '\x00');
  for (int kind = 0; kind < 10; ++kind) kinds += fuzz::envelope_record(kind, 0, "");
  write(dir / "every_kind_unassigned", kinds);
  std::string sizes(1, '\x01');
  runtime::Command two;
  two.set_time(0.001);
  two.add_drift(1e-3);
  two.add_drift(2e-3);
  sizes += fuzz::envelope_record(runtime::COMMAND, 1, two.SerializeAsString());
  sizes += fuzz::envelope_record(runtime::COMMAND, 1 << 30, command(1.0, 1.0, 1.0));
  write(dir / "wrong_sizes", sizes);
  // Unassigned nodes get their ASSIGN over the wire (the fuzzer mutates the study inside it).
  std::string assigned_by_message(1, '\x00');
  assigned_by_message += fuzz::envelope_record(
      runtime::ASSIGN, 0,
      fuzz::paper_assign(1, config::NodeSpec::SUBSTRUCTURE).SerializeAsString());
  for (int k = 1; k <= 3; ++k)
    assigned_by_message +=
        fuzz::envelope_record(runtime::COMMAND, k, command(k * 0.001, 1e-4 * k, 0.1));
  write(dir / "assign_message", assigned_by_message);
  std::string foreign(1, '\x03');
  foreign += fuzz::envelope_record(runtime::COMMAND, 1, command(0.001, 1e-4, 0.1));
  write(dir / "foreign_run", foreign);
  return 0;
}
