#include "fuzz/targets.h"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <stdexcept>

#include "actuator_emulator/actuator_service.h"
#include "controller_node/frame.h"
#include "deploy/sites.h"
#include "identify/model/data.h"
#include "results/results.h"
#include "results/write.h"
#include "runtime/node/plan.h"
#include "runtime/node/schema.h"
#include "runtime/node/validation.h"
#include "runtime/record/record.h"
#include "study/motion_files.h"
#include "study/study.h"
#include "study/text_format.h"
#include "substructure_nodes/substructure_service.h"

namespace rths::fuzz {
namespace {

namespace fs = std::filesystem;

// The paper's frame (configs/paper_frame.textproto) without its motion: what the deployment and
// envelope targets assign and plan against.
constexpr const char* kPaperFrame =
    "name: \"paper_frame\"\n"
    "structure { sdof { period: 0.5 mass: 1000 } damping { modal_zeta: 0.05 } }\n"
    "motion { path: \"unused.AT2\" }\n"
    "integrator { kind: EXPLICIT_NEWMARK dt: 0.001 }\n"
    "substructuring { experimental_fraction: 0.3333333333333333 model { linear {} } }\n"
    "cases { name: \"reference\" }\n"
    "cases { name: \"lag_shift_14ms\" delay { shift { delay: 0.014 } } }\n";
constexpr double kPaperDt = 0.001;
constexpr const char* kRunId = "fuzz";

std::string as_text(const std::uint8_t* data, std::size_t size) {
  return std::string(reinterpret_cast<const char*>(data), size);
}

// The one scratch file of this process; rewritten for every input.
class FuzzScratch {
 public:
  FuzzScratch() : dir_(fs::temp_directory_path() / ("rths_fuzz_" + std::to_string(getpid()))) {
    fs::create_directories(dir_);
  }
  ~FuzzScratch() {
    std::error_code ignored;
    fs::remove_all(dir_, ignored);
  }
  const fs::path& write(const std::uint8_t* data, std::size_t size) {
    std::ofstream out(input_, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
    return input_;
  }
  fs::path output() const { return dir_ / "output.csv"; }

 private:
  fs::path dir_;
  fs::path input_ = dir_ / "input";
};

FuzzScratch& scratch() {
  static FuzzScratch instance;
  return instance;
}

// Runs `body`; the documented errors of bad input end it quietly.
template <class Body>
int guarded(Body body) {
  try {
    body();
  } catch (const std::invalid_argument&) {
  } catch (const std::runtime_error&) {}
  return 0;
}

const config::Study& paper_frame() {
  static const config::Study study = study::parse_study(kPaperFrame, "paper_frame");
  return study;
}

const core::HybridSetup& paper_setup() {
  static const core::HybridSetup setup = runtime::setup_without_motion(
      paper_frame(), fs::temp_directory_path(), kPaperDt, paper_frame().cases(0));
  return setup;
}

std::uint32_t read_le(const std::uint8_t* p, int bytes) {
  std::uint32_t value = 0;
  for (int i = bytes - 1; i >= 0; --i) value = (value << 8) | p[i];
  return value;
}

}  // namespace

runtime::Assign paper_assign(int node_id, config::NodeSpec::Kind kind) {
  runtime::Assign assign;
  assign.set_schema_version(runtime::kSchemaVersion);
  *assign.mutable_study() = paper_frame();
  assign.set_base_dir(fs::temp_directory_path().string());
  assign.set_case_name("lag_shift_14ms");
  assign.mutable_node()->set_id(node_id);
  assign.mutable_node()->set_kind(kind);
  assign.set_dt(kPaperDt);
  assign.add_storeys(0);
  if (kind == config::NodeSpec::ACTUATOR_EMULATOR) assign.add_actuators(0);
  assign.set_heartbeat_period(0.05);
  assign.set_orphan_timeout(2.0);
  return assign;
}

int study_config(const std::uint8_t* data, std::size_t size) {
  return guarded([&] {
    const config::Study study = study::parse_study(as_text(data, size), "fuzz");
    study::validate_study(study, "fuzz");
    const double dt = study.integrator().dt() > 0 ? study.integrator().dt() : 0.01;
    runtime::setup_without_motion(study, fs::temp_directory_path(), dt,
                                  study::find_case(study, ""));
  });
}

int deployment_config(const std::uint8_t* data, std::size_t size) {
  return guarded([&] {
    config::Deployment deployment;
    study::parse_text_format(as_text(data, size), "fuzz", deployment);
    runtime::make_plan(paper_setup(), runtime::with_default_nodes(deployment, paper_setup()));
  });
}

int sites_config(const std::uint8_t* data, std::size_t size) {
  return guarded([&] { deploy::parse_sites(as_text(data, size), "fuzz"); });
}

int at2_motion(const std::uint8_t* data, std::size_t size) {
  return guarded([&] { study::read_at2(scratch().write(data, size)); });
}

int column_motion(const std::uint8_t* data, std::size_t size) {
  const fs::path& file = scratch().write(data, size);
  guarded([&] { study::read_columns(file, 0.01, core::kGravity); });
  return guarded([&] { study::read_columns(file, 0.0, 1.0); });
}

int daq_export(const std::uint8_t* data, std::size_t size) {
  return guarded([&] { identify::read_measured(scratch().write(data, size), {}, {}, 2); });
}

int run_record(const std::uint8_t* data, std::size_t size) {
  return guarded([&] {
    const runtime::RecordContents contents = runtime::read_record(scratch().write(data, size));
    results::write_table(results::record_table(contents), scratch().output(),
                         results::Format::kCsv);
  });
}

std::string flip_test_record(int steps) {
  std::string bytes(runtime::record_preamble());
  runtime::RecordEntry entry;
  runtime::RunHeader& h = *entry.mutable_header();
  h.set_schema_version(runtime::kSchemaVersion);
  h.set_run_id(kRunId);
  *h.mutable_study() = paper_frame();
  h.set_clock("real_time");
  h.set_dt(kPaperDt);
  h.set_dofs(1);
  h.set_actuators(1);
  h.add_link_node_ids(1);
  h.add_link_node_ids(2);
  runtime::append_record_frame(entry, bytes);
  for (int k = 0; k < steps; ++k) {
    entry.Clear();
    runtime::StepRecord& s = *entry.mutable_step();
    s.set_step(k);
    s.set_time(k * kPaperDt);
    s.add_displacement(0.01 * std::sin(0.05 * k));
    s.add_command(0.01 * std::sin(0.05 * (k - 14)));
    s.add_measured_force(-1e3 * std::sin(0.05 * k));
    for (int node : {1, 2}) {
      runtime::LinkSample& link = *s.add_links();
      link.set_node_id(node);
      link.set_answered_step(k);
      link.set_round_trip(2e-4 + 1e-6 * (k % 7));
    }
    runtime::append_record_frame(entry, bytes);
    if (k % 100 == 99) {
      entry.Clear();
      entry.mutable_event()->set_step(k);
      entry.mutable_event()->set_what("an event at step " + std::to_string(k));
      runtime::append_record_frame(entry, bytes);
    }
  }
  entry.Clear();
  entry.mutable_footer()->set_ok(true);
  entry.mutable_footer()->set_status("completed");
  entry.mutable_footer()->mutable_counters()->set_steps(
      static_cast<std::uint64_t>(std::max(steps - 1, 0)));
  runtime::append_record_frame(entry, bytes);
  return bytes;
}

FlipVerdict& FlipVerdict::operator+=(const FlipVerdict& o) {
  entries += o.entries, damaged += o.damaged, intact += o.intact, detected += o.detected;
  recovered += o.recovered, silent += o.silent, unreported += o.unreported;
  lost_intact += o.lost_intact;
  return *this;
}

FlipVerdict check_flipped_record(const std::string& original, const std::string& damaged) {
  const runtime::RecordContents truth = runtime::parse_record(original, "original");
  runtime::RecordContents read;
  try {
    read = runtime::parse_record(damaged, "damaged");
  } catch (const std::runtime_error&) {  // nothing of a record left: every entry dropped
  }
  FlipVerdict v;
  std::map<std::uint64_t, std::size_t> read_at;  // offset -> index in `read`
  for (std::size_t j = 0; j < read.offsets.size(); ++j) read_at[read.offsets[j]] = j;
  for (std::size_t i = 0; i < truth.offsets.size(); ++i) {
    const std::uint64_t first = truth.offsets[i];
    const std::uint64_t end = i + 1 < truth.offsets.size() ? truth.offsets[i + 1] : original.size();
    const bool hit = original.compare(first, end - first, damaged, first, end - first) != 0;
    const auto found = read_at.find(first);
    const bool read_there = found != read_at.end();
    const bool back = read_there && read.entries[found->second].SerializeAsString() ==
                                        truth.entries[i].SerializeAsString();
    if (read_there) read_at.erase(found);
    ++v.entries;
    if (!hit) {
      ++v.intact;
      ++(back ? v.recovered : v.lost_intact);
      continue;
    }
    ++v.damaged;
    bool reported = false;
    for (const runtime::RecordLoss& loss : read.losses)
      reported = reported || (loss.first_byte <= first && end <= loss.end_byte);
    if (read_there)
      ++v.silent;
    else if (reported)
      ++v.detected;
    else
      ++v.unreported;
  }
  v.silent += read_at.size();  // entries read at an offset where none was written
  return v;
}

std::string flips_input(int steps,
                        const std::vector<std::pair<std::uint32_t, std::uint8_t>>& flips) {
  std::string out;
  const auto n = static_cast<std::uint32_t>(std::max(steps - 1, 0));
  out.push_back(static_cast<char>(n & 0xff));
  out.push_back(static_cast<char>((n >> 8) & 0xff));
  for (const auto& [position, mask] : flips) {
    for (int i = 0; i < 4; ++i) out.push_back(static_cast<char>((position >> (8 * i)) & 0xff));
    out.push_back(static_cast<char>(mask));
  }
  return out;
}

int record_flips(const std::uint8_t* data, std::size_t size) {
  if (size < 2) return 0;
  const std::string original = flip_test_record(1 + static_cast<int>(read_le(data, 2) % 1024));
  std::string damaged = original;
  for (std::size_t at = 2; at + 5 <= size; at += 5) {
    const std::uint8_t mask = data[at + 4] != 0 ? data[at + 4] : 0x01;
    char& byte = damaged[read_le(data + at, 4) % damaged.size()];
    byte = static_cast<char>(byte ^ mask);
  }
  const FlipVerdict v = check_flipped_record(original, damaged);
  if (!v.holds())
    throw std::logic_error("record_flips: " + std::to_string(v.silent) + " silent, " +
                           std::to_string(v.unreported) + " unreported, " +
                           std::to_string(v.lost_intact) + " intact entries lost");
  return 0;
}

std::string envelope_record(std::int32_t kind, std::int32_t step, const std::string& payload) {
  std::string out;
  out.push_back(static_cast<char>(kind));
  for (int i = 0; i < 4; ++i)
    out.push_back(static_cast<char>((static_cast<std::uint32_t>(step) >> (8 * i)) & 0xff));
  const std::size_t n = std::min<std::size_t>(payload.size(), 0xffff);
  out.push_back(static_cast<char>(n & 0xff));
  out.push_back(static_cast<char>(n >> 8));
  out.append(payload, 0, n);
  return out;
}

int envelope_payload(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  const std::uint8_t flags = data[0];
  substructure_nodes::SubstructureService substructure(1, "");
  actuator_emulator::ActuatorService actuator(2, "");
  runtime::NodeService* services[] = {&substructure, &actuator};
  if (flags & 1) {
    const auto assign = [](int id, config::NodeSpec::Kind kind) {
      return runtime::pack(kRunId, id, runtime::ASSIGN, 0, paper_assign(id, kind));
    };
    substructure.handle(assign(1, config::NodeSpec::SUBSTRUCTURE));
    actuator.handle(assign(2, config::NodeSpec::ACTUATOR_EMULATOR));
  }
  std::size_t at = 1;
  while (at + 7 <= size) {
    transport::Message m;
    m.run_id = (flags & 2) ? "another-run" : kRunId;
    m.kind = data[at];
    m.step = static_cast<std::int32_t>(read_le(data + at + 1, 4));
    const std::size_t n = read_le(data + at + 5, 2);
    at += 7;
    m.payload = as_text(data + at, std::min(n, size - at));
    at += m.payload.size();
    runtime::check_envelope(m, kRunId);
    for (runtime::NodeService* service : services) {
      m.node_id = service->node_id();
      guarded([&] { service->handle(m); });
    }
  }
  return 0;
}

namespace {

bool same_values(const controller_node::FrameValues& a, const controller_node::FrameValues& b) {
  return a.counter == b.counter && a.status == b.status && a.has_status == b.has_status &&
         a.time == b.time && a.target_displacement == b.target_displacement &&
         a.target_velocity == b.target_velocity &&
         a.measured_displacement == b.measured_displacement && a.measured_force == b.measured_force;
}

}  // namespace

int controller_frame(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  const int fields = 1 + (data[0] & 0x0F);
  const auto direction = (data[0] & 0x80) ? controller_node::Direction::kFeedback
                                          : controller_node::Direction::kCommand;
  constexpr int kActuators = 2;
  if (size < 1 + 2 * static_cast<std::size_t>(fields)) return 0;
  config::FrameLayout layout;
  for (int i = 0; i < fields; ++i) {
    const std::uint8_t role = data[1 + 2 * i], bits = data[2 + 2 * i];
    config::FrameField& f = *layout.add_fields();
    f.set_role(static_cast<config::FrameField::Role>(role % 9));
    f.set_type(static_cast<config::FrameField::Type>(bits & 3));
    f.set_byte_order((bits & 4) ? config::FrameField::ORDER_BIG : config::FrameField::ORDER_LITTLE);
    f.set_actuator((bits >> 3) & 1);
  }
  try {
    runtime::check_frame_layout(layout, kActuators, direction, "fuzz");
  } catch (const std::invalid_argument&) {
    return 0;
  }
  const std::uint8_t* frame = data + 1 + 2 * fields;
  const std::size_t frame_bytes = size - 1 - 2 * static_cast<std::size_t>(fields);
  controller_node::FrameValues first, second;
  if (controller_node::decode(layout, frame, frame_bytes, kActuators, first) !=
      controller_node::FrameVerdict::kOk)
    return 0;
  std::vector<std::uint8_t> bytes;
  if (!controller_node::encode(layout, first, bytes))
    throw std::logic_error("a decoded frame does not encode again");
  if (controller_node::decode(layout, bytes.data(), bytes.size(), kActuators, second) !=
          controller_node::FrameVerdict::kOk ||
      !same_values(first, second))
    throw std::logic_error("a frame decoded, encoded and decoded again differs");
  return 0;
}

const std::vector<Target>& targets() {
  static const std::vector<Target> all{
      {"study_config", &study_config},
      {"deployment_config", &deployment_config},
      {"sites_config", &sites_config},
      {"at2_motion", &at2_motion},
      {"column_motion", &column_motion},
      {"daq_export", &daq_export},
      {"run_record", &run_record},
      {"envelope_payload", &envelope_payload},
      {"record_flips", &record_flips},
      {"study_values", &study_values},
      {"controller_frame", &controller_frame},
  };
  return all;
}

}  // namespace rths::fuzz
