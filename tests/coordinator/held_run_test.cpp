// A run held from the view (coordinator/state.h hold_run): what a node's own HOLD means there.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>
#include <vector>

#include "actuator_emulator/actuator_service.h"
#include "coordinator/coordinator.h"
#include "runtime/node/hold_cause.h"
#include "runtime/record/record.h"
#include "substructure_nodes/substructure_service.h"
#include "tests/runtime/test_support.h"
#include "transport/in_process.h"
#include "view/control_room.h"

namespace rths {
namespace {

// The run's outcome and the record's events, one per line.
struct RecordedRun {
  coordinator::RunOutcome outcome;
  std::string events;
};

// A run held from the view (lab_a's operator holds node 1 at step 20), seen from node 2 (lab_b's
// emulator, not held): it answers each of the coordinator's heartbeats with its own (it stays
// alive); at the first heartbeat after the run is held it holds on its own with `cause`, at the
// next the director presses STOP.
class HeldRunNode final : public transport::NodeHandler {
 public:
  HeldRunNode(runtime::NodeService& service, view::ControlDesk& desk, bool* run_held,
              std::string cause)
      : service_(service), desk_(desk), run_held_(run_held), cause_(std::move(cause)) {}
  std::vector<transport::Message> start() override { return service_.start(); }
  std::vector<transport::Message> handle(const transport::Message& m) override {
    auto replies = service_.handle(m);
    if (m.kind == runtime::HOLD) *run_held_ = true;
    if (m.kind == runtime::COMMAND && m.step == 20 && !cause_.empty())
      desk_.press(desk_.crew().operators.at("lab_a"), "hold", "lab_a", m.step);
    if (m.kind != runtime::HEARTBEAT) return replies;
    replies.push_back(service_.heartbeat());
    if (cause_.empty() || !*run_held_ || pressed_stop_) return replies;
    if (const auto hold = service_.hold_on_own(cause_)) {
      replies.push_back(*hold);
    } else {
      desk_.press(desk_.crew().director, "stop", "");
      pressed_stop_ = true;
    }
    return replies;
  }

 private:
  runtime::NodeService& service_;
  view::ControlDesk& desk_;
  bool* run_held_;
  std::string cause_;
  bool pressed_stop_ = false;
};

RecordedRun held_run(const std::string& cause, const std::string& record_name) {
  const auto record = std::filesystem::temp_directory_path() / record_name;
  const study::PreparedStudy prepared = test::prepare(test::paper_frame_study(
      2.0,
      "deployment { nodes { id: 1 kind: SUBSTRUCTURE } nodes { id: 2 kind: ACTUATOR_EMULATOR } }"));
  view::ControlDesk desk(view::Crew::make({"lab_a", "lab_b"}), {{"lab_a", {1}}, {"lab_b", {2}}});
  coordinator::CoordinatorOptions options;
  options.run_id = "run";
  options.case_name = "reference";
  options.record = record;
  options.control = &desk;
  transport::InProcessTransport transport;
  substructure_nodes::SubstructureService substructure{1, "run"};
  actuator_emulator::ActuatorService emulator{2, "run"};
  bool run_held = false;
  HeldRunNode node1(substructure, desk, &run_held, "");
  HeldRunNode node2(emulator, desk, &run_held, cause);
  coordinator::Coordinator coordinator(prepared, transport, options);
  transport.attach(1, node1);
  transport.attach(2, node2);
  RecordedRun r;
  r.outcome = coordinator.run();
  for (const auto& entry : runtime::read_record(record).entries)
    if (entry.has_event()) r.events += entry.event().what() + "\n";
  return r;
}

// In a held run no command leaves: a node's command watchdog HOLD is expected there and only
// recorded; the run ends by the director's STOP, naming who held it and no node.
TEST(Coordinator, AHeldRunRecordsANodesCommandWatchdogHold) {
  const RecordedRun r = held_run(
      std::string(runtime::kCommandWatchdogCause) + "40.0 ms (limit 30.0 ms)", "held_watchdog.rec");
  EXPECT_FALSE(r.outcome.ok);
  EXPECT_EQ(r.outcome.status, std::string(coordinator::kStoppedFromView) +
                                  " by the director (held: HOLD from the view by the operator "
                                  "of lab_a)");
  EXPECT_EQ(r.outcome.failed_node, "");
  EXPECT_NE(r.events.find("node 2 (actuator emulator) held on its own at its step 20 while the "
                          "run is held: command watchdog: no fresh command for 40.0 ms"),
            std::string::npos)
      << r.events;
}

// Any other HOLD of a node's own (its limits, its controller) is its fault, held run or not: the
// run ends at once naming the node and the cause.
TEST(Coordinator, AHeldRunEndsNamingANodesOwnHoldForAFault) {
  const RecordedRun r =
      held_run("step 20: force limit: |force| 2e+05 N beyond 1e+05 N", "held_fault.rec");
  EXPECT_FALSE(r.outcome.ok);
  EXPECT_EQ(r.outcome.failed_node, "node 2 (actuator emulator)");
  EXPECT_NE(r.outcome.status.find("held on its own at its step 20: step 20: force limit: |force| "
                                  "2e+05 N beyond 1e+05 N (while held: HOLD from the view by the "
                                  "operator of lab_a)"),
            std::string::npos)
      << r.outcome.status;
  EXPECT_EQ(r.outcome.status.find(coordinator::kStoppedFromView), std::string::npos)
      << r.outcome.status;
}

}  // namespace
}  // namespace rths
