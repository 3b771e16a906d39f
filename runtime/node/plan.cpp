#include "runtime/node/plan.h"

#include <fmt/format.h>

#include <sys/resource.h>
#include <unistd.h>

#include <cmath>

#include <algorithm>
#include <map>
#include <set>
#include <stdexcept>

#include "runtime/node/lag.h"
#include "runtime/node/schema.h"

namespace rths::runtime {

std::string NodePlan::label() const {
  return "node " + std::to_string(spec.id()) + " (" + node_kind_name(spec.kind()) + ")";
}

const NodePlan* DeploymentPlan::find(int node_id) const {
  for (const NodePlan& n : nodes)
    if (n.spec.id() == node_id) return &n;
  return nullptr;
}

namespace {

// The storeys (from 0) a node hosts: those it names (from 1), each with a part of its kind, or
// without names every storey of the pool.
std::vector<int> hosted_storeys(const config::NodeSpec& spec, const std::set<int>& pool,
                                int storeys, bool sub, const std::string& where) {
  std::vector<int> hosted;
  if (spec.storeys().empty()) {
    hosted.assign(pool.begin(), pool.end());
  } else {
    for (int s1 : spec.storeys()) {
      if (s1 < 1 || s1 > storeys)
        throw std::invalid_argument(where + ": storey " + std::to_string(s1) +
                                    " does not exist (1.." + std::to_string(storeys) + ")");
      if (!pool.count(s1 - 1))
        throw std::invalid_argument(where + ": storey " + std::to_string(s1) + " has no " +
                                    (sub ? "numerical" : "experimental") + " part");
      hosted.push_back(s1 - 1);
    }
    std::sort(hosted.begin(), hosted.end());
  }
  return hosted;
}

// Each storey has one host of a kind.
void claim_storeys(const std::vector<int>& hosted, int node_id, std::map<int, int>& host) {
  for (int s : hosted) {
    const auto [it, fresh] = host.emplace(s, node_id);
    if (!fresh)
      throw std::invalid_argument("storey " + std::to_string(s + 1) + " is hosted by nodes " +
                                  std::to_string(it->second) + " and " + std::to_string(node_id));
  }
}

}  // namespace

namespace {
// A controller node needs its link; only it carries one, and it carries no compensation (the
// lab's controller runs its own).
void check_controller_spec(const config::NodeSpec& spec, const std::string& where) {
  const bool controller = spec.kind() == config::NodeSpec::CONTROLLER;
  if (controller != spec.has_controller())
    throw std::invalid_argument(where + (controller ? ": a CONTROLLER needs its `controller` link"
                                                    : ": only a CONTROLLER carries `controller`"));
  if (controller && spec.compensation_size() > 0)
    throw std::invalid_argument(where +
                                ": a CONTROLLER carries no compensation; the lab's controller "
                                "runs its own");
}

// The hosted storeys of a partition, by the kind of node that may host them.
struct StoreyPools {
  int storeys = 0;
  std::set<int> numerical, experimental;
};

// One node's plan from its spec: its kind, storeys and actuators checked against the pools and
// claimed in `host` (storey -> node id). Throws std::invalid_argument naming `where`.
NodePlan plan_node(const config::NodeSpec& spec, const core::HybridSetup& base,
                   const config::Deployment& deployment, const StoreyPools& pools,
                   std::map<int, int>& host, const std::string& where) {
  const auto& partition = base.partition;
  NodePlan node;
  node.spec = spec;
  const bool sub = spec.kind() == config::NodeSpec::SUBSTRUCTURE;
  if (!sub && !drives_actuators(spec.kind()))
    throw std::invalid_argument(where +
                                ": kind must be SUBSTRUCTURE, ACTUATOR_EMULATOR or CONTROLLER");
  check_controller_spec(spec, where);
  if (sub && spec.compensation_size() > 0)
    throw std::invalid_argument(where +
                                ": compensation shapes actuator commands; only an "
                                "ACTUATOR_EMULATOR carries it");
  const std::set<int>& pool = sub ? pools.numerical : pools.experimental;
  const std::vector<int> hosted = hosted_storeys(spec, pool, pools.storeys, sub, where);
  claim_storeys(hosted, spec.id(), host);
  node.storeys = hosted;
  if (sub && partition.coupled_to(hosted) != hosted)
    throw std::invalid_argument(where +
                                ": the numerical stiffness matrix couples its DOFs to "
                                "others; one substructure node hosts every coupled DOF");
  if (!sub) {
    for (std::size_t a = 0; a < partition.actuator_storeys.size(); ++a)
      if (std::count(hosted.begin(), hosted.end(), partition.actuator_storeys[a]))
        node.actuators.push_back(static_cast<int>(a));
  }
  if (spec.kind() == config::NodeSpec::CONTROLLER)
    check_controller_link(spec.controller(), answer_window(deployment, base.dt),
                          static_cast<int>(node.actuators.size()), where);
  return node;
}

}  // namespace

DeploymentPlan make_plan(const core::HybridSetup& base, const config::Deployment& deployment) {
  const auto& partition = base.partition;
  StoreyPools pools;
  pools.storeys = static_cast<int>(partition.numerical.size());
  for (int s = 0; s < pools.storeys; ++s)
    if (partition.has_numerical(s)) pools.numerical.insert(s);
  for (int s : partition.actuator_storeys) pools.experimental.insert(s);

  check_failsafe_windows(deployment);
  DeploymentPlan plan;
  std::set<int> ids;
  std::map<int, int> numerical_host, experimental_host;  // storey -> node id
  bool any_substructure = false;
  for (const config::NodeSpec& spec : deployment.nodes()) {
    const std::string where = "deployment.nodes[id " + std::to_string(spec.id()) + "]";
    if (spec.id() < 1)
      throw std::invalid_argument(where + ": id must be >= 1 (0 is the coordinator)");
    if (!ids.insert(spec.id()).second)
      throw std::invalid_argument(where + ": id used by two nodes");
    const bool sub = spec.kind() == config::NodeSpec::SUBSTRUCTURE;
    any_substructure |= sub;
    plan.nodes.push_back(
        plan_node(spec, base, deployment, pools, sub ? numerical_host : experimental_host, where));
  }
  plan.numerical_local = !any_substructure;
  if (any_substructure)
    for (int s : pools.numerical)
      if (!numerical_host.count(s))
        throw std::invalid_argument("numerical " + partition.channel_name(s) +
                                    " is hosted by no substructure node");
  for (int s : pools.experimental)
    if (!experimental_host.count(s))
      throw std::invalid_argument(
          "experimental " + partition.channel_name(s) +
          (s >= partition.dofs() ? " (storeys: " + std::to_string(s + 1) + " in a node)" : "") +
          " is hosted by no actuator emulator or controller (deployment.nodes)");
  (void)with_node_compensation(base, plan);  // refuses bad blocks before any node is started
  return plan;
}

DeploymentPlan plan_deployment(const core::HybridSetup& base,
                               const config::Deployment& deployment) {
  return make_plan(base, with_default_nodes(deployment, base));
}

core::HybridSetup with_node_compensation(core::HybridSetup setup, const DeploymentPlan& plan) {
  for (const NodePlan& node : plan.nodes)
    study::apply_compensation(setup, node.actuators, node.spec.compensation(),
                              "deployment.nodes[id " + std::to_string(node.spec.id()) + "]");
  return setup;
}

void check_node_stages(const DeploymentPlan& plan, double dt,
                       const std::filesystem::path& base_dir) {
  for (const NodePlan& node : plan.nodes) {
    const std::string where = "deployment.nodes[id " + std::to_string(node.spec.id()) + "]";
    for (const auto& [field, stages] : {std::pair{".receive_delay", &node.spec.receive_delay()},
                                        std::pair{".send_delay", &node.spec.send_delay()}}) {
      try {
        (void)study::make_delay_chain(*stages, dt, base_dir);
      } catch (const std::invalid_argument& e) {
        throw std::invalid_argument(where + field + ": " + e.what());
      }
    }
  }
}

config::Deployment with_default_nodes(config::Deployment deployment,
                                      const core::HybridSetup& base) {
  if (deployment.nodes_size() > 0) return deployment;
  bool numerical = false;
  for (int s = 0; s < static_cast<int>(base.partition.numerical.size()); ++s)
    numerical = numerical || base.partition.has_numerical(s);
  if (numerical) {
    auto* node = deployment.add_nodes();
    node->set_id(1);
    node->set_kind(config::NodeSpec::SUBSTRUCTURE);
  }
  if (!base.partition.actuator_storeys.empty()) {
    auto* node = deployment.add_nodes();
    node->set_id(2);
    node->set_kind(config::NodeSpec::ACTUATOR_EMULATOR);
  }
  return deployment;
}

void check_deployment(const study::PreparedStudy& prepared) {
  const core::HybridSetup setup =
      study::setup_for_case(prepared, study::reference_case(prepared.config));
  const DeploymentPlan plan = plan_deployment(setup, prepared.config.deployment());
  check_node_stages(plan, setup.dt, prepared.base_dir);
}

core::HybridSetup setup_without_motion(const config::Study& study,
                                       const std::filesystem::path& base_dir, double dt,
                                       const config::Case& study_case,
                                       const std::function<void(const std::string&)>& phase) {
  study::PreparedStudy prepared;
  prepared.config = study;
  prepared.base_dir = base_dir;
  if (phase) phase("reading and checking the study's structure");
  prepared.base = study::base_setup(study, dt, base_dir);
  if (phase)
    phase("building case '" + study_case.name() + "' on the " +
          std::to_string(prepared.base.model.dofs()) + "-DOF structure");
  return study::setup_for_case(prepared, study_case);
}

namespace {
double or_default(double value, double fallback) { return value > 0 ? value : fallback; }
}  // namespace

double start_timeout(const config::Deployment& d) { return or_default(d.start_timeout(), 10.0); }
double heartbeat_period(const config::Deployment& d) {
  return or_default(d.heartbeat_period(), 0.05);
}
double liveliness_timeout(const config::Deployment& d) {
  return or_default(d.liveliness_timeout(), 1.0);
}
double judged_liveliness_timeout(const config::Deployment& d) {
  if (d.clock() == config::Deployment::REAL_TIME) return liveliness_timeout(d);
  return std::max(liveliness_timeout(d), kLockstepLivelinessFloor);
}
double step_timeout(const config::Deployment& d) { return or_default(d.step_timeout(), 2.0); }
double feedback_wait_fraction(const config::Deployment& d) {
  return or_default(d.feedback_wait_fraction(), 0.5);
}
bool awaits_answers(const config::Deployment& d, const config::NodeSpec& node, double dt) {
  const double round_trip = node.receive_lag().one_way_delay() + node.send_lag().one_way_delay();
  return round_trip < feedback_wait_fraction(d) * dt;
}
WaitPolicy wait_policy(const config::Deployment& d) {
  WaitPolicy policy;
  switch (d.wait_policy()) {
    case config::WAIT_SLEEP_THEN_SPIN: policy.kind = WaitPolicyKind::kSleepThenSpin; break;
    case config::WAIT_SPIN: policy.kind = WaitPolicyKind::kSpin; break;
    default: policy.kind = WaitPolicyKind::kSleep; break;
  }
  policy.spin_margin_ns = std::llround(or_default(d.spin_margin(), 200e-6) * 1e9);
  return policy;
}
namespace {
bool may_raise_to(int priority) {
  if (geteuid() == 0) return true;
  rlimit limit{};
  return getrlimit(RLIMIT_RTPRIO, &limit) == 0 &&
         (limit.rlim_cur == RLIM_INFINITY || limit.rlim_cur >= static_cast<rlim_t>(priority));
}
}  // namespace

int realtime_priority(const config::Deployment& d) {
  return d.realtime_priority() > 0 && d.clock() == config::Deployment::REAL_TIME &&
                 d.wait_policy() != config::WAIT_SPIN
             ? d.realtime_priority()
             : 0;
}

std::string realtime_priority_text(const config::Deployment& d) {
  if (d.clock() != config::Deployment::REAL_TIME) return "off (lockstep)";
  if (d.realtime_priority() > 0) return fmt::format("SCHED_FIFO {} (set)", d.realtime_priority());
  if (d.realtime_priority() < 0) return "off (realtime_priority: -1)";
  if (!may_raise_to(kRecommendedFifoPriority))
    return fmt::format(
        "off (unset; this process could not raise itself: it needs root, "
        "CAP_SYS_NICE or an RLIMIT_RTPRIO of {})",
        kRecommendedFifoPriority);
  return fmt::format(
      "off (unset: realtime_priority: {} keeps a loaded host's other work off the "
      "loop, docs/realtime.md)",
      kRecommendedFifoPriority);
}

double max_overrun_fraction(const config::Deployment& d) {
  return d.max_overrun_fraction() == 0 ? 0.001 : d.max_overrun_fraction();
}
double min_answer_fraction(const config::Deployment& d) {
  return d.min_answer_fraction() == 0 ? 0.99 : d.min_answer_fraction();
}
namespace {
constexpr int kDefaultWindowSteps = 3;
constexpr double kMaxWindowMs = 60'000.0;

int window_steps(double window_ms, int steps, double dt) {
  if (window_ms > 0) {
    // The tolerance keeps a window of exactly k steps at k (ms / dt in floating point).
    const double exact = window_ms * 1e-3 / dt;
    return std::max(1, static_cast<int>(std::ceil(exact - 1e-9)));
  }
  return steps > 0 ? steps : kDefaultWindowSteps;
}

void check_window(double window_ms, const char* ms_field, int steps, const char* steps_field) {
  if (!std::isfinite(window_ms) || window_ms < 0 || window_ms > kMaxWindowMs)
    throw std::invalid_argument("deployment." + std::string(ms_field) + " = " +
                                std::to_string(window_ms) + " ms: must be in [0, 60000] ms");
  if (window_ms > 0 && steps > 0)
    throw std::invalid_argument("deployment." + std::string(ms_field) + " and deployment." +
                                steps_field + " both given (" + std::to_string(window_ms) +
                                " ms and " + std::to_string(steps) +
                                " steps): give the window one way");
}
}  // namespace

int max_missed_answers(const config::Deployment& d, double dt) {
  return window_steps(d.answer_window_ms(), d.max_missed_answers(), dt);
}
int command_watchdog_periods(const config::Deployment& d, double dt) {
  // Unset, the watchdog is no shorter than the answer window: a lab that widened that window for
  // its platform's stalls would otherwise see the same stalls trip a 3-period watchdog.
  if (!(d.command_watchdog_ms() > 0) && d.command_watchdog_periods() <= 0)
    return std::max(kDefaultWindowSteps, max_missed_answers(d, dt));
  return window_steps(d.command_watchdog_ms(), d.command_watchdog_periods(), dt);
}
double window_ms_of_steps(int steps, double dt) {
  return std::floor(static_cast<double>(steps) * dt * 1e6) / 1e3;
}
AnswerWindow answer_window(const config::Deployment& d, double dt) {
  AnswerWindow window;
  window.real_time = d.clock() == config::Deployment::REAL_TIME;
  window.dt = dt;
  window.steps = max_missed_answers(d, dt);
  window.step_timeout = step_timeout(d);
  return window;
}

void check_failsafe_windows(const config::Deployment& d) {
  check_window(d.answer_window_ms(), "answer_window_ms", d.max_missed_answers(),
               "max_missed_answers");
  check_window(d.command_watchdog_ms(), "command_watchdog_ms", d.command_watchdog_periods(),
               "command_watchdog_periods");
}

std::string controller_checks_text(const config::ControllerLink& link,
                                   const config::Deployment& deployment, double dt) {
  const AnswerWindow window = answer_window(deployment, dt);
  const bool real_time = window.real_time;
  const double floor = controller_jump_floor(link);
  const double rate = link.max_measured_rate() > 0 ? link.max_measured_rate()
                                                   : 2.0 * deployment.limits().max_velocity();
  const auto on = [](double v, const std::string& text) { return v > 0 ? text : "off"; };
  return fmt::format(
      "controller checks: reply timeout {:.3f} ms; answer window {}; command watchdog {}; hold "
      "time {:.0f} ms; measured rate {}; measured jump {}; tracking {}; force rate {}; max force "
      "{}",
      controller_reply_timeout(link, window) * 1e3,
      real_time ? fmt::format("{} steps ({:.3f} ms)", window.steps, window.seconds() * 1e3)
                : fmt::format("lockstep step timeout {:.3f} s", window.step_timeout),
      real_time ? fmt::format("{} periods ({:.3f} ms)", command_watchdog_periods(deployment, dt),
                              command_watchdog_periods(deployment, dt) * dt * 1e3)
                : std::string("off (lockstep)"),
      controller_hold_time(link) * 1e3, on(rate, fmt::format("<= {:.3f} m/s", rate)),
      on(floor, fmt::format("<= 2 x peak target velocity x span + {:.3f} mm", floor * 1e3)),
      link.max_tracking_error() > 0
          ? fmt::format("<= {:.3f} mm for {} answers", link.max_tracking_error() * 1e3,
                        link.tracking_error_steps() > 0 ? link.tracking_error_steps() : 3)
          : fmt::format("<= 2 x peak target velocity x {:.1f} ms + {:.3f} mm for {} answers",
                        controller_expected_lag(link) * 1e3, (floor + 1e-3) * 1e3,
                        link.tracking_error_steps() > 0 ? link.tracking_error_steps() : 3),
      on(link.max_force_rate(), fmt::format("<= {:g} N/s", link.max_force_rate())),
      on(link.max_force(), fmt::format("<= {:g} N", link.max_force())));
}

}  // namespace rths::runtime
