#include "deploy/joint_lag_sites.h"

#include <optional>
#include <sstream>
#include <stdexcept>

#include "analysis/compare.h"
#include "core/metrics.h"
#include "core/simulation.h"
#include "core/study.h"
#include "deploy/netns.h"
#include "deploy/sites.h"
#include "runtime/measurements.h"
#include "runtime/record.h"

namespace rths::deploy {
namespace {

using analysis::JointLagPoint;
using analysis::JointLagResult;
using analysis::JointLagStudy;

void run_measured(const JointLagStudy& config, const std::filesystem::path& base_dir,
                  JointLagResult& result, const std::function<void()>& one_done) {
  const std::filesystem::path& out = result.output_directory;
  const auto sites_file = base_dir / config.sites();
  const double duration = config.measured_duration() > 0.0 ? config.measured_duration() : 5.0;
  for (const double round_trip : config.measured_network_round_trips()) {
    for (const double actuator : config.measured_actuator_lags()) {
      auto plan = load_sites(sites_file);
      plan.study.mutable_motion()->set_duration(duration);
      auto& deployment = *plan.study.mutable_deployment();
      const bool real_time = deployment.clock() == config::Deployment::REAL_TIME;
      auto* joint_case = plan.study.add_cases();
      joint_case->set_name("joint_actuator");
      *joint_case->add_delay() =
          analysis::joint_lag_actuator_stage(config.actuator_model(), actuator);
      deployment.set_case_name("joint_actuator");
      for (auto& node : *deployment.mutable_nodes()) {
        if (node.kind() != config::NodeSpec::ACTUATOR_EMULATOR) continue;
        // Only the delay: the study's point is the injected round trip, without jitter or loss.
        config::LinkLag lag;
        lag.set_one_way_delay(round_trip / 2);
        *node.mutable_receive_lag() = lag;
        *node.mutable_send_lag() = lag;
      }
      std::ostringstream name;
      name << "measured_R" << round_trip * 1e3 << "ms_A" << actuator * 1e3 << "ms";
      const auto run = run_sites(plan, {out / name.str(), std::nullopt, {}});
      if (!run.ok) throw std::runtime_error("across-sites run " + name.str() + ": " + run.status);

      JointLagPoint point;
      point.network_round_trip = round_trip;
      point.actuator_lag = actuator;
      for (const auto& link : run.links) {
        if (link.kind == "actuator_emulator") point.measured_round_trip = link.round_trip.median;
      }
      const runtime::RunMeasurements measured =
          runtime::measure_run(runtime::read_record(run.record));
      const core::SimulationResult& steps = measured.steps;
      if (steps.command.cols() == 0 || steps.displacement.cols() == 0)
        throw std::runtime_error("across-sites run " + name.str() + ": record has no actuator");
      const std::vector<double> command = analysis::column_of(steps.command, 0),
                                realised = analysis::column_of(steps.realised, 0),
                                u = analysis::column_of(steps.displacement, 0);
      const double dt = steps.dt;
      if (command.size() < 10 || !(dt > 0.0)) {
        throw std::runtime_error("across-sites run " + name.str() + ": record too short");
      }
      // Real time: the coordinator pairs each command with the newest feedback it has, which
      // answers an older step when the round trip exceeds the wait, so the realised displacement
      // it records lags the command by round trip + actuator lag. Lockstep: each command is
      // paired with its own answer, so J1 sees the actuator alone and the network part is the
      // measured round trip.
      const double j1 =
          core::j1_delay(command, realised, dt, analysis::joint_lag_search_window(config));
      point.measured_total_lag = real_time ? j1 : point.measured_round_trip + j1;
      point.measured_actuator_lag = real_time ? j1 - point.measured_round_trip : j1;
      point.real_time = real_time;
      point.duration = duration;
      // The in-process reference over the same duration.
      auto reference_study = plan.study;
      const auto prepared = core::prepare_study(reference_study, base_dir);
      const auto reference = core::simulate(
          core::setup_for_case(prepared, core::reference_case(reference_study)), prepared.motion);
      analysis::fill_joint_lag_errors(point, analysis::floor_history(reference, 0), u,
                                      measured.has_footer && measured.footer.diverged());
      result.measured.push_back(point);
      one_done();
    }
  }
}

}  // namespace

analysis::JointLagAcrossSites joint_lag_across_sites() { return {namespace_support, run_measured}; }

}  // namespace rths::deploy
