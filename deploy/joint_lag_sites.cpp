#include "deploy/joint_lag_sites.h"

#include <optional>
#include <sstream>
#include <stdexcept>

#include "analysis/common/compare.h"
#include "core/metrics.h"
#include "core/simulation.h"
#include "deploy/netns.h"
#include "deploy/sites.h"
#include "runtime/record/measurements.h"
#include "runtime/record/record.h"
#include "study/study.h"

namespace rths::deploy {
namespace {

using analysis::JointLagPoint;
using analysis::JointLagResult;
using analysis::JointLagStudy;

// The record's lags and error of one across-sites run (see the header for real time and
// lockstep), and the in-process runs over the same stretch: the reference, and what the
// response can see (lockstep never lets the network lag in).
void judge_run(const JointLagStudy& config, const SitesPlan& plan, const config::Case& joint_case,
               const std::filesystem::path& base_dir, const SitesRunResult& run,
               JointLagPoint& point) {
  const std::string name = run.record.stem().string();
  for (const auto& link : run.links)
    if (link.kind == "actuator_emulator") point.measured_round_trip = link.round_trip.median;
  const runtime::RunMeasurements measured = runtime::measure_run(runtime::read_record(run.record));
  const core::SimulationResult& steps = measured.steps;
  if (steps.command.cols() == 0 || steps.displacement.cols() == 0)
    throw std::runtime_error("across-sites run " + name + ": record has no actuator");
  const std::vector<double> command = analysis::column_of(steps.command, 0),
                            realised = analysis::column_of(steps.realised, 0),
                            u = analysis::column_of(steps.displacement, 0);
  if (command.size() < 10 || !(steps.dt > 0.0))
    throw std::runtime_error("across-sites run " + name + ": record too short");
  // Real time: the coordinator pairs each command with the newest feedback it has, which answers
  // an older step when the round trip exceeds the wait, so the realised displacement it records
  // lags the command by round trip + actuator lag. Lockstep: each command is paired with its own
  // answer, so J1 sees the actuator alone and the network part is the measured round trip.
  const double j1 =
      core::j1_delay(command, realised, steps.dt, analysis::joint_lag_search_window(config));
  point.measured_total_lag = point.real_time ? j1 : point.measured_round_trip + j1;
  point.measured_actuator_lag = point.real_time ? j1 - point.measured_round_trip : j1;
  auto study = plan.study;
  const auto prepared = study::prepare_study(study, base_dir);
  const auto simulate = [&](const config::Case& c) {
    return core::simulate(study::setup_for_case(prepared, c), prepared.motion);
  };
  const auto reference = simulate(study::reference_case(study));
  const std::vector<double> u_ref = analysis::floor_history(reference, 0);
  analysis::fill_joint_lag_errors(point, u_ref, u,
                                  measured.has_footer && measured.footer.diverged());
  config::Case seen = joint_case;
  if (point.real_time) {
    seen.clear_delay();
    seen.add_delay()->mutable_shift()->set_delay(point.network_round_trip);
    *seen.add_delay() =
        analysis::joint_lag_actuator_stage(config.actuator_model(), point.actuator_lag);
  }
  const auto in_process = simulate(seen);
  const analysis::Comparison c =
      analysis::compare(u_ref, analysis::floor_history(in_process, 0), in_process.diverged);
  point.in_process_rms_error_pct = c.rms_error_pct;
  point.in_process_nrmse = c.nrmse_pct / 100.0;
}

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
      const auto run = run_sites(plan, {out / name.str(), std::nullopt, {}, {}, false, -1.0, {}});
      if (!run.ok) throw std::runtime_error("across-sites run " + name.str() + ": " + run.status);
      JointLagPoint point;
      point.network_round_trip = round_trip;
      point.actuator_lag = actuator;
      point.real_time = deployment.clock() == config::Deployment::REAL_TIME;
      point.duration = duration;
      judge_run(config, plan, *joint_case, base_dir, run, point);
      result.measured.push_back(point);
      one_done();
    }
  }
}

}  // namespace

analysis::JointLagAcrossSites joint_lag_across_sites() { return {namespace_support, run_measured}; }

}  // namespace rths::deploy
