#pragma once
// Deployment plan: which node hosts which storeys, checked against the study's partition.
//
// Rules (errors name the node id and storey, 1-based):
//   node ids unique and >= 1 (0 is the coordinator); kind set.
//   A substructure node hosts numerical storeys (empty list = all of them). If no substructure node
//   is declared the coordinator evaluates the numerical storeys itself; otherwise every numerical
//   storey is hosted by exactly one node.
//   An actuator emulator hosts experimental storeys (empty = all); every experimental storey is
//   hosted by exactly one emulator.
//   Only an actuator emulator carries `compensation`; its blocks are checked (count, fields, not
//   also given by the case) against the setup's actuators.
// Also: the node-side view of a study (what a node builds from its Assign without the motion file).

#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "runtime/node/controller_link.h"
#include "runtime/rt/wait_policy.h"

#include "rths/proto/deployment.pb.h"
#include "study/study.h"

namespace rths::runtime {

struct NodePlan {
  config::NodeSpec spec;
  std::vector<int> storeys;    // 0-based, ascending: numerical storeys or actuator storeys
  std::vector<int> actuators;  // emulators: actuator indices (into partition.actuator_storeys)
  std::string label() const;   // "node 2 (substructure)"
};

struct DeploymentPlan {
  std::vector<NodePlan> nodes;
  bool numerical_local = false;  // the coordinator evaluates the numerical storeys
  const NodePlan* find(int node_id) const;
};

DeploymentPlan make_plan(const core::HybridSetup& base, const config::Deployment& deployment);
// The deployment as a run runs it: with_default_nodes (below), then make_plan. The one planning
// the coordinator, the in-process wiring and the record's readers (answer_sources.h) use, so
// they assign the same nodes. Throws as make_plan.
DeploymentPlan plan_deployment(const core::HybridSetup& base, const config::Deployment& deployment);

// The setup with each actuator emulator's `compensation` in front of the chains of the actuators it
// hosts (study::apply_compensation): what the emulators run, so what an in-process run must use to
// equal a lockstep distributed run. Throws std::invalid_argument naming the node.
core::HybridSetup with_node_compensation(core::HybridSetup setup, const DeploymentPlan& plan);

// Builds every node's receive_delay / send_delay chain once (at dt, Trace paths relative to
// base_dir), so a bad stage is bad input before any node starts. Throws std::invalid_argument
// naming the node and the field.
void check_node_stages(const DeploymentPlan& plan, double dt,
                       const std::filesystem::path& base_dir);

// The deployment with default nodes when it declares none: node 1 a substructure node (if any
// storey has a numerical part), node 2 an actuator emulator (if any has an experimental part).
config::Deployment with_default_nodes(config::Deployment deployment, const core::HybridSetup& base);

// The study's deployment planned for its reference case (the default nodes, make_plan,
// check_node_stages), as `launch` plans it for a case: the nodes, their links, windows and
// compensation. Every command that reads a study calls it (`rths run`, `launch`, `sites`), so
// they refuse the same deployments with the same message. Other cases may be meant for
// in-process runs only (a case's own compensator where a node carries one): `launch` plans the
// case it runs again. Throws std::invalid_argument naming the node and the field.
void check_deployment(const study::PreparedStudy& prepared);

// The setup of one case built without reading the motion (a node on another host may not have
// it): the same structure, partition and delay chains as study::prepare_study + setup_for_case.
// `phase`, if given, is told each of its two phases as it starts (the structure read and checked,
// then the case's setup on it), for a node's set-up progress (setup_progress.h).
core::HybridSetup setup_without_motion(
    const config::Study& study, const std::filesystem::path& base_dir, double dt,
    const config::Case& study_case, const std::function<void(const std::string&)>& phase = nullptr);

// Defaults of the deployment's timing fields (0 means default), in s.
double start_timeout(const config::Deployment& d);
double heartbeat_period(const config::Deployment& d);
double liveliness_timeout(const config::Deployment& d);
// How long a node may be silent before the coordinator declares it dead (and, doubled, how long
// a node outlives a silent coordinator): liveliness_timeout in real time; in lockstep at least
// kLockstepLivelinessFloor, because a lockstep result cannot depend on timing and a busy machine
// starves a process for over a second (1.41 s seen with a browser on the run's two CPUs).
inline constexpr double kLockstepLivelinessFloor = 5.0;  // s
double judged_liveliness_timeout(const config::Deployment& d);
double step_timeout(const config::Deployment& d);
double feedback_wait_fraction(const config::Deployment& d);
// Real time: whether the loop waits (feedback_wait_fraction x dt) for a node's answer to the step
// it just commanded; not for a node whose link injects a round trip at least that long.
bool awaits_answers(const config::Deployment& d, const config::NodeSpec& node, double dt);
WaitPolicy wait_policy(const config::Deployment& d);
// The SCHED_FIFO priority a run's real-time threads take (runtime/rt/fifo.h), 0 = none:
// realtime_priority when set (1-98) in a real-time run that does not spin; unset (0) or -1,
// none. Opt-in, not a default: several runs raised on one small host (a test suite's, at -j2)
// exhaust the kernel's real-time bandwidth (95 % a second) and are frozen together for tens of
// ms, where ordinary threads would only have been delayed. kRecommendedFifoPriority is what the
// pre-run check recommends: beside two builds a real-time dry run missed its deadlines in 6 of 6
// runs unprioritised and in 0 of 6 at 50 (bench/controller_flood.py, docs/controller.md).
inline constexpr int kRecommendedFifoPriority = 50;
int realtime_priority(const config::Deployment& d);
// "SCHED_FIFO 20 (set)", "off (unset: realtime_priority: 50 keeps ...)", "off (lockstep)": how
// the run's threads will be scheduled, and the recommendation, for the pre-run check.
std::string realtime_priority_text(const config::Deployment& d);
double max_overrun_fraction(const config::Deployment& d);  // < 0: not checked
double min_answer_fraction(const config::Deployment& d);   // < 0: not checked
// The fail-safe windows in steps of dt (s): answer_window_ms / command_watchdog_ms when given
// (ceil(ms / dt), at least 1), else max_missed_answers / command_watchdog_periods, else 3; the
// command watchdog of an actuator emulator or controller node, when neither of its fields is
// given, is the answer window (at least 3 periods).
int max_missed_answers(const config::Deployment& d, double dt);
int command_watchdog_periods(const config::Deployment& d, double dt);
// The window a controller's answers must arrive within (the reply timeout's bound).
AnswerWindow answer_window(const config::Deployment& d, double dt);
// One line a person reads before the run (the controller node logs it when assigned): the
// reply timeout, the answer window, the command watchdog, the hold time and every plausibility
// check of the controller link with its bound (or "off").
std::string controller_checks_text(const config::ControllerLink& link,
                                   const config::Deployment& deployment, double dt);
// The window of `steps` whole steps of dt (s) in ms, truncated to the microsecond below, so that
// the steps derived from it (as above) are `steps` again: what a window is stated as when it was
// found in steps.
double window_ms_of_steps(int steps, double dt);
// Throws std::invalid_argument naming the field, its value and the allowed range when a window
// is given both in steps and in ms, or its ms value is not in [0, 60000] (0 = not given).
void check_failsafe_windows(const config::Deployment& d);

}  // namespace rths::runtime
