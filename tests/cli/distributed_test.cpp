// cli/distributed: the exit status of distributed cases and what their summary says, on results
// built by hand (no process runs).
#include "cli/distributed.h"

#include <gtest/gtest.h>

#include "cli/commands.h"

namespace rths::cli {
namespace {

DistributedRun run_with_exit(int code) { return {"reference", code, "", "x.rthsrec", "logs"}; }

int exit_of(const DistributedResults& results, const std::vector<DistributedRun>& runs) {
  try {
    fail_if_distributed_failed(results, runs, false);
  } catch (const ExitError& e) {
    return e.code;
  }
  return 0;
}

// One completed case, as judge_distributed leaves it.
DistributedResults one_case() {
  DistributedResults results;
  analysis::CaseOutcome c;
  c.name = "reference";
  results.outcome.cases.push_back(c);
  results.facts.emplace_back();
  results.links.emplace_back();
  return results;
}

TEST(FailIfDistributedFailed, AKilledOrTimedOutCoordinatorIsAFailedRun) {
  const DistributedResults results = one_case();
  EXPECT_EQ(exit_of(results, {run_with_exit(0)}), 0);
  EXPECT_EQ(exit_of(results, {run_with_exit(1)}), kExitRunFailed);
  EXPECT_EQ(exit_of(results, {run_with_exit(128 + 9)}), kExitRunFailed) << "SIGKILL";
  EXPECT_EQ(exit_of(results, {run_with_exit(124)}), kExitRunFailed) << "--timeout";
  EXPECT_EQ(exit_of(results, {run_with_exit(2)}), kExitBadInput);
  EXPECT_EQ(exit_of(results, {run_with_exit(3)}), kExitEnvironment);
}

TEST(FailIfDistributedFailed, ALockstepRunThatDiffersFromInProcessFailsNamingTheFirstStep) {
  DistributedResults results = one_case();
  results.facts[0].difference_from_in_process = analysis::InProcessDifference{0.0, std::nullopt};
  EXPECT_EQ(exit_of(results, {run_with_exit(0)}), 0) << "bit for bit";
  results.facts[0].difference_from_in_process = analysis::InProcessDifference{2.5e-3, 17};
  try {
    fail_if_distributed_failed(results, {run_with_exit(0)}, false);
    FAIL() << "passed";
  } catch (const ExitError& e) {
    EXPECT_EQ(e.code, kExitRunFailed);
    EXPECT_NE(std::string(e.what()).find("differs from the in-process run from step 17"),
              std::string::npos)
        << e.what();
  }
}

TEST(DistributedSummary, NamesTheFirstDifferingStepAndEveryNodesRejects) {
  DistributedResults results = one_case();
  results.facts[0].difference_from_in_process = analysis::InProcessDifference{2.5e-3, 17};
  runtime::NodeRejects node;
  node.set_node_id(2);
  node.set_label("node 2 (actuator emulator)");
  node.mutable_rejected()->set_not_entitled(5);
  node.mutable_rejected()->set_foreign_run(1);
  node.mutable_rejected()->set_unauthenticated(7);  // its transport's drops, from its heartbeat
  node.set_final(true);
  results.facts[0].node_rejects.push_back(node);
  const std::string text = analysis::distributed_summary_text(results);
  EXPECT_NE(text.find("DIFFERS from the in-process run of the same case from step 17"),
            std::string::npos)
      << text;
  EXPECT_NE(text.find("node 2 (actuator emulator) DDS messages rejected: foreign_run 1, "
                      "not_entitled 5, "
                      "unauthenticated 7"),
            std::string::npos)
      << text;
  const nlohmann::json j = analysis::distributed_summary_json(results);
  EXPECT_EQ(j["cases"][0]["first_step_differing_from_in_process"], 17);
  EXPECT_EQ(j["cases"][0]["node_rejects"][0]["rejected"]["not_entitled"], 5);
  EXPECT_EQ(j["cases"][0]["node_rejects"][0]["rejected"]["unauthenticated"], 7);
}

// The per-step cost and the start-up come from the record (each step's step_wall, and step 1's
// start against the header's), and the summary prints them.
TEST(DistributedSummary, SaysTheStepsWorkAndHowLongAfterStartUpStep1Began) {
  runtime::RecordContents record;
  runtime::RecordEntry header;
  header.mutable_header()->set_start_realtime_ns(1'000'000'000);
  record.entries.push_back(header);
  for (int k = 0; k <= 100; ++k) {
    runtime::RecordEntry e;
    e.mutable_step()->set_step(k);
    e.mutable_step()->set_step_wall(k == 0 ? 5.0 : 1e-5 * k);  // step 0 has no exchange
    if (k > 0) e.mutable_step()->set_start_realtime_ns(3'500'000'000 + k * 1'000'000);
    record.entries.push_back(e);
  }
  const analysis::StepTiming timing = analysis::step_timing(record);
  EXPECT_NEAR(timing.work_median, 5e-4, 1.1e-5);
  EXPECT_NEAR(timing.work_p99, 9.9e-4, 1.1e-5);
  EXPECT_DOUBLE_EQ(timing.start_to_step1, 2.501);
  DistributedResults results = one_case();
  results.outcome.cases[0].simulation.dt = 0.001;
  results.facts[0].timing = timing;
  const std::string text = analysis::distributed_summary_text(results);
  EXPECT_NE(text.find("step work median 0.50"), std::string::npos) << text;
  EXPECT_NE(text.find("step 1 began 2.501 s after the coordinator started up"), std::string::npos)
      << text;
  EXPECT_DOUBLE_EQ(analysis::distributed_summary_json(results)["cases"][0]["start_to_step1_s"],
                   2.501);
}

}  // namespace
}  // namespace rths::cli
