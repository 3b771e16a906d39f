// `rths export` on records whose checksums hold but whose footer, inputs, link samples or timings
// disagree with what was written (runtime/record/record_checks.h): each kind is named, `--strict`
// exits 1 and `--json` says "ok": false; the same record whole exports as ok.
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

}  // namespace
