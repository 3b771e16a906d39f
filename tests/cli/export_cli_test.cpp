// `rths export` on records whose checksums hold but whose footer, inputs, link samples or timings
// disagree with what was written (runtime/record/record_checks.h): each kind is named, `--strict`
// exits 1 and `--json` says "ok": false; the same record whole exports as ok. Also: an output
// that is the input is refused, CRC-valid nonsense is named, a record cut short fails only
// --strict, and a controller's hold is written beside each output.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <functional>
#include <limits>
#include <nlohmann/json.hpp>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "runtime/node/schema.h"
#include "runtime/record/record.h"
#include "tests/cli/cli_support.h"
#include "util/crc32c.h"

namespace {

using namespace rths::cli_test;
using rths::runtime::RecordEntry;

constexpr std::int64_t kLastStep = 1999;

RecordEntry header_entry() {
  RecordEntry e;
  e.mutable_header()->set_schema_version(rths::runtime::kSchemaVersion);
  e.mutable_header()->set_dt(0.001);
  e.mutable_header()->set_dofs(1);
  e.mutable_header()->set_actuators(1);
  return e;
}

RecordEntry step_entry(std::int64_t k) {
  RecordEntry e;
  rths::runtime::StepRecord& s = *e.mutable_step();
  s.set_step(k);
  s.set_time(0.001 * static_cast<double>(k));
  s.add_displacement(0.0);
  s.add_command(0.0);
  if (k > 0) {
    rths::runtime::LinkSample& link = *s.add_links();
    link.set_node_id(2);
    link.set_answered_step(k);
    link.set_round_trip(2e-4);
  }
  return e;
}

RecordEntry footer_entry() {
  RecordEntry e;
  e.mutable_footer()->set_ok(true);
  e.mutable_footer()->set_status("completed");
  e.mutable_footer()->mutable_counters()->set_steps(kLastStep);
  return e;
}

// Steps 0-1999 and a footer counting them, every frame intact, after `change` (which may drop
// or alter entries) was applied to the entries.
std::string record_bytes(const std::function<void(std::vector<RecordEntry>&)>& change) {
  std::vector<RecordEntry> entries{header_entry()};
  for (std::int64_t k = 0; k <= kLastStep; ++k) entries.push_back(step_entry(k));
  entries.push_back(footer_entry());
  change(entries);
  std::string bytes(rths::runtime::record_preamble());
  for (const RecordEntry& e : entries) rths::runtime::append_record_frame(e, bytes);
  return bytes;
}

// The step entry of step k (entry 0 is the header).
rths::runtime::StepRecord& step_of(std::vector<RecordEntry>& entries, std::int64_t k) {
  return *entries[static_cast<std::size_t>(k) + 1].mutable_step();
}

// The JSON document on stdout, between the warnings before it and the error after it.
nlohmann::json json_in(const std::string& output) {
  const auto start = output.find("{\n");
  const auto end = output.find("\n}\n", start);
  return nlohmann::json::parse(output.substr(start, end + 2 - start));
}

const double kNan = std::numeric_limits<double>::quiet_NaN();

TEST(ExportCli, EachKindOfRecordThatDisagreesWithWhatWasWrittenIsNamedAndNotOk) {
  const auto dir = scratch("export_disagree");
  using Change = std::function<void(std::vector<RecordEntry>&)>;
  const std::vector<std::tuple<std::string, Change, std::string>> kinds{
      {"lost_steps",
       [](auto& e) { e.erase(e.begin() + 1001, e.begin() + 2001); },  // steps 1000-1999
       "and the last intact step is 999: steps 1000-1999 are absent with no damaged region"},
      {"no_inputs", [](auto& e) { e[0].mutable_header()->set_inputs_crc32c(0xabcdef); },
       "no inputs entry: the header names one (CRC-32C abcdef)"},
      {"link_nan", [](auto& e) { step_of(e, 7).mutable_links(0)->set_round_trip(kNan); },
       "entry 8 (step 7): links[0] (node 2): round_trip is not finite"},
      {"link_inf",
       [](auto& e) {
         step_of(e, 7).mutable_links(0)->set_one_way_up(std::numeric_limits<double>::infinity());
       },
       "links[0] (node 2): one_way_up is not finite"},
      {"link_negative", [](auto& e) { step_of(e, 9).mutable_links(0)->set_injected_lag(-0.25); },
       "entry 10 (step 9): links[0] (node 2): injected_lag -0.25 s is negative"},
      {"link_future", [](auto& e) { step_of(e, 9).mutable_links(0)->set_answered_step(50); },
       "answered_step 50 is after this step (an answer from the future)"},
      {"link_prediction",
       [](auto& e) { step_of(e, 9).mutable_links(0)->add_prediction_error(kNan); },
       "prediction_error[0] is not finite"},
      {"lateness_nan", [](auto& e) { step_of(e, 5).set_lateness(kNan); },
       "entry 6 (step 5): lateness is not finite"},
      {"step_wall_negative", [](auto& e) { step_of(e, 5).set_step_wall(-1.0); },
       "entry 6 (step 5): step_wall -1 s is not a time span"},
  };
  const std::string whole = (dir / "whole.rthsrec").string();
  std::ofstream(whole, std::ios::binary) << record_bytes([](auto&) {});
  Outcome o =
      run("export " + whole + " --csv " + (dir / "whole.csv").string() + " --strict --json");
  ASSERT_EQ(o.exit_code, 0) << o.output;
  EXPECT_TRUE(json_in(o.output)["ok"].get<bool>()) << o.output;
  for (const auto& [name, change, named] : kinds) {
    SCOPED_TRACE(name);
    const std::string record = (dir / (name + ".rthsrec")).string();
    std::ofstream(record, std::ios::binary) << record_bytes(change);
    o = run("export " + record + " --csv " + (dir / (name + ".csv")).string() + " --strict --json");
    EXPECT_EQ(o.exit_code, 1) << o.output;
    EXPECT_NE(o.output.find(named), std::string::npos) << o.output;
    const nlohmann::json j = json_in(o.output);
    EXPECT_FALSE(j["ok"].get<bool>()) << o.output;
    EXPECT_FALSE(j["problems"].empty()) << o.output;
  }
}

// An output that is one of the command's inputs is refused before anything is written.
TEST(CliTest, ExportNeverOverwritesTheRecordItReads) {
  const auto dir = scratch("export");
  const auto record = dir / "R.rthsrec";
  std::filesystem::copy_file(kSource / "fuzz/corpus/run_record/header_only.rthsrec", record);
  const auto size = std::filesystem::file_size(record);
  Outcome o = run("export " + record.string() + " --csv " + record.string());
  EXPECT_EQ(o.exit_code, 2) << o.output;
  EXPECT_NE(o.output.find("--csv '" + record.string() + "' is the input record"), std::string::npos)
      << o.output;
  EXPECT_EQ(std::filesystem::file_size(record), size);
  o = run("export " + record.string() + " --csv " + (dir / "R.csv").string());
  EXPECT_EQ(o.exit_code, 0) << o.output;
}

rths::runtime::RecordEntry crafted_header(double dt) {
  rths::runtime::RecordEntry e;
  rths::runtime::RunHeader& h = *e.mutable_header();
  h.set_schema_version(rths::runtime::kSchemaVersion);
  h.set_dt(dt);
  h.set_dofs(1);
  h.set_actuators(1);
  return e;
}

rths::runtime::RecordEntry crafted_step(std::int64_t k, double time, double u = 0.0) {
  rths::runtime::RecordEntry e;
  e.mutable_step()->set_step(k);
  e.mutable_step()->set_time(time);
  e.mutable_step()->add_displacement(u);
  e.mutable_step()->add_command(0.0);
  return e;
}

// A record of these entries, each framed with valid checksums as the writer frames them; `forged`
// goes in raw before entry `forged_at`.
std::string crafted_record(const std::vector<rths::runtime::RecordEntry>& entries,
                           const std::string& forged = "", std::size_t forged_at = 0) {
  std::string bytes(rths::runtime::record_preamble());
  for (std::size_t i = 0; i < entries.size(); ++i) {
    if (i == forged_at) bytes += forged;
    rths::runtime::append_record_frame(entries[i], bytes);
  }
  return bytes;
}

// The attack's CRC-valid nonsense: each kind is named on stderr and `--strict` exits non-zero.
TEST(CliTest, ExportNamesEachKindOfChecksummedNonsenseAndStrictExitsNonZero) {
  const auto dir = scratch("export_sense");
  rths::runtime::RecordEntry footer;
  footer.mutable_footer()->set_status("completed");
  // The header, steps 0-4 at 0.01 s, then the footer.
  const auto steps = [&footer](const rths::runtime::RecordEntry& header) {
    std::vector<rths::runtime::RecordEntry> e{header};
    for (int k = 0; k < 5; ++k) e.push_back(crafted_step(k, k * 0.01));
    e.push_back(footer);
    return e;
  };
  rths::runtime::RecordEntry other_dt = crafted_header(0.02);
  // A 16-byte frame header whose own checksum holds, claiming 4 GB.
  std::string fake("\xF3\x7A\x1C\xB5\xF0\xFF\xFF\xFF\0\0\0\0", 12);
  const std::uint32_t crc = rths::util::crc32c(fake.data(), 12);
  for (int i = 0; i < 4; ++i) fake.push_back(static_cast<char>((crc >> (8 * i)) & 0xFFu));
  const std::vector<std::tuple<std::string, std::string, std::string>> cases{
      {"dt_nan", crafted_record(steps(crafted_header(std::nan("")))),
       "entry 0 (header): dt nan s is not a time step"},
      {"dt_zero", crafted_record(steps(crafted_header(0))),
       "entry 0 (header): dt 0 s is not a time step"},
      {"dt_negative", crafted_record(steps(crafted_header(-1))),
       "entry 0 (header): dt -1 s is not a time step"},
      {"gap",
       crafted_record(
           {crafted_header(0.01), crafted_step(0, 0), crafted_step(1000000000, 1e7), footer}),
       "entry 2 (step 1000000000): steps 1-999999999 are absent before it"},
      {"backwards",
       crafted_record({crafted_header(0.01), crafted_step(0, 0), crafted_step(1, 0.01),
                       crafted_step(2, -5), footer}),
       "entry 3 (step 2): time -5 s is before the step before's 0.01 s (time goes back)"},
      {"huge_u",
       crafted_record(
           {crafted_header(0.01), crafted_step(0, 0), crafted_step(1, 0.01, 1e300), footer}),
       "entry 2 (step 1): displacement[0] = 1e+300 m is beyond a plausible 1000 m"},
      {"copies_disagree",
       crafted_record(
           {crafted_header(0.01), crafted_step(0, 0), other_dt, crafted_step(1, 0.01), footer}),
       "entry 2 (header copy): disagrees with the header in entry 0: modified: dt: 0.01 -> 0.02"},
      {"fake_frame", crafted_record(steps(crafted_header(0.01)), fake, 3), "bytes "},
  };
  for (const auto& [name, bytes, named] : cases) {
    SCOPED_TRACE(name);
    const auto record = dir / (name + ".rthsrec");
    std::ofstream(record, std::ios::binary) << bytes;
    const Outcome o = run("export " + record.string() + " --csv " +
                          (dir / (name + ".csv")).string() + " --strict");
    EXPECT_EQ(o.exit_code, 1) << o.output;
    EXPECT_NE(o.output.find(named), std::string::npos) << o.output;
    EXPECT_NE(o.output.find("rths export: warning: "), std::string::npos) << o.output;
  }
  // The fake frame hides none of the 5 steps behind it.
  const Outcome fake_read =
      run("export " + (dir / "fake_frame.rthsrec").string() + " --csv " + (dir / "f.csv").string());
  EXPECT_NE(fake_read.output.find("wrote 5 steps"), std::string::npos) << fake_read.output;
  EXPECT_NE(fake_read.output.find("(16 bytes): no step lost"), std::string::npos)
      << fake_read.output;
}

// A sound record cut short exports with a warning and exit 0; `--strict` makes that exit 1.
TEST(CliTest, ExportStrictRefusesARecordCutShort) {
  const auto dir = scratch("export_strict");
  const auto record = dir / "cut.rthsrec";
  std::ofstream(record, std::ios::binary)
      << crafted_record({crafted_header(0.01), crafted_step(0, 0), crafted_step(1, 0.01)});
  const std::string csv = " --csv " + (dir / "cut.csv").string();
  Outcome o = run("export " + record.string() + csv);
  EXPECT_EQ(o.exit_code, 0) << o.output;
  EXPECT_NE(o.output.find("no footer"), std::string::npos) << o.output;
  o = run("export " + record.string() + csv + " --strict");
  EXPECT_EQ(o.exit_code, 1) << o.output;
  EXPECT_NE(o.output.find("--strict: the record is not whole"), std::string::npos) << o.output;
}

// A controller's hold, frame by frame, goes beside each output in its format, and into --json.
TEST(CliTest, ExportWritesTheControllersHoldBesideEachOutput) {
  const auto dir = scratch("export_hold");
  rths::runtime::RecordEntry footer;
  footer.mutable_footer()->set_status("controller: implausible measurement");
  rths::runtime::NodeRejects& node = *footer.mutable_footer()->add_node_rejects();
  node.set_node_id(2);
  node.set_label("node 2 (controller)");
  for (const auto kind : {rths::runtime::HoldEntry::SENT_HOLD, rths::runtime::HoldEntry::ANSWER,
                          rths::runtime::HoldEntry::SENT_STOP}) {
    rths::runtime::HoldEntry* e = node.mutable_controller()->add_hold_log();
    e->set_kind(kind);
    e->set_counter(40 + static_cast<int>(kind));
    e->add_position(0.0021);
    if (kind == rths::runtime::HoldEntry::ANSWER) e->add_force(12.5);
    e->set_verdict(kind == rths::runtime::HoldEntry::ANSWER ? "held" : "");
  }
  const auto record = dir / "held.rthsrec";
  std::ofstream(record, std::ios::binary)
      << crafted_record({crafted_header(0.01), crafted_step(0, 0), crafted_step(1, 0.01), footer});
  const Outcome o = run("export " + record.string() + " --csv " + (dir / "held.csv").string() +
                        " --h5 " + (dir / "held.h5").string() + " --json");
  const std::size_t open = o.output.find('{');
  ASSERT_NE(open, std::string::npos) << o.output;
  const auto j =
      nlohmann::json::parse(o.output.substr(open, o.output.rfind('}') + 1 - open), nullptr, false);
  ASSERT_FALSE(j.is_discarded()) << o.output;
  EXPECT_EQ(j["hold_tables"].size(), 2u) << o.output;
  EXPECT_TRUE(std::filesystem::exists(dir / "held_hold.h5"));
  std::ifstream csv(dir / "held_hold.csv");
  std::string head, line;
  std::getline(csv, head);
  EXPECT_EQ(head, "node,entry,kind,time_s,frame,status,position1_m,force1_N,verdict") << head;
  int rows = 0;
  while (std::getline(csv, line)) ++rows;
  EXPECT_EQ(rows, 3);
  EXPECT_EQ(j["node_health"]["2"]["controller"]["hold"]["entries"][1]["force_N"][0], 12.5);
}

}  // namespace
