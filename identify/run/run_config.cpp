#include "identify/run/run_config.h"

#include <cmath>
#include <numeric>
#include <stdexcept>

#include "identify/fit/effect_parameters.h"
#include "identify/model/study_config.h"
#include "identify/run/sensors.h"
#include "study/study.h"
#include "study/text_format.h"
#include "util/atomic_file.h"

namespace rths::identify {
namespace {

std::filesystem::path trace_path(const std::filesystem::path& dir, int node_id) {
  return std::filesystem::absolute(dir / ("lag_node_" + std::to_string(node_id) + ".csv"));
}

// The measured round trip as a fitted distribution, split evenly over both ways.
void fit_link_lag(const NetworkPath& link, config::NodeSpec& node) {
  const auto n = static_cast<double>(link.round_trip.size());
  const double mean = std::accumulate(link.round_trip.begin(), link.round_trip.end(), 0.0) / n;
  double var = 0.0;
  for (double r : link.round_trip) var += (r - mean) * (r - mean) / n;
  const double lost = static_cast<double>(link.lost) / (n + static_cast<double>(link.lost));
  for (config::LinkLag* lag : {node.mutable_receive_lag(), node.mutable_send_lag()}) {
    lag->set_one_way_delay(0.5 * mean);
    lag->set_jitter(std::sqrt(var / 2.0));
    lag->set_loss(1.0 - std::sqrt(1.0 - lost));
  }
}

// The stages the run applied to a command (run_residual.h declared_case), as the identified case:
// what an actuator the record did not contradict keeps.
config::Case declared_stages(const config::Study& study, const config::Case* run_case) {
  config::Case out = declared_case(study, run_case ? *run_case : config::Case{});
  out.clear_compensation();
  out.set_name(kIdentifiedCaseName);
  return out;
}

// The moving parameters of actuator `actuator` the re-run held (run_residual.h moving): a delay
// as its trace stage in `study_case`, a stiffness or a gain as its constant with a note saying so.
void hold_moving(const RunIdentification& run, int actuator, config::Case& study_case,
                 std::vector<std::string>& notes) {
  if (!run.residual) return;
  for (const MovingRerun& m : run.residual->moving) {
    if (!m.kept || m.parameter.actuator != actuator) continue;
    if (!hold_moving_delay(m.parameter, study_case))
      notes.push_back(moving_not_written(m.parameter));
  }
}

// The identified actuator cases: one when every actuator has the same stages, else one each.
std::vector<config::Case> actuator_cases(const RunIdentification& run, const config::Case* run_case,
                                         std::vector<std::string>& notes) {
  std::vector<config::Case> out;
  for (const auto& path : run.actuators) {
    if (!path.id.find(Channel::kMeasured)) continue;
    const RigModels rig = rig_models(path);
    config::Case study_case = declared_stages(run.study, run_case);
    if (rig.actuator) {
      const ChannelSignals& signals = identified_signals(path.id, Channel::kMeasured);
      const SignalScales scales = signal_scales(signals);
      ActuatorCase part = actuator_case(*rig.actuator, scales, kIdentifiedCaseName,
                                        RigRecord{signals.time.front(), scales.duration});
      for (const auto& l : part.left_out)
        notes.push_back("actuator " + std::to_string(path.actuator) + ": " + l);
      study_case = part.study_case;
    }
    hold_moving(run, path.actuator, study_case, notes);
    if (rig.actuator && !rig.specimen)
      keep_declared_force_stages(declared_stages(run.study, run_case), study_case);
    if (rig.specimen) {
      const ChannelSignals& f = identified_signals(path.id, Channel::kForce);
      const SignalScales force_scales = signal_scales(f);
      add_force_stages(*rig.specimen, force_scales,
                       RigRecord{f.time.front(), force_scales.duration}, study_case,
                       rig.held_by_declared);
    }
    add_displacement_scale(rig.displacement_scale, study_case);
    if (run_case) *study_case.mutable_compensation() = run_case->compensation();
    out.push_back(study_case);
  }
  bool same = true;
  for (const auto& c : out) same = same && c.SerializeAsString() == out.front().SerializeAsString();
  if (same && out.size() > 1) out.resize(1);
  if (out.size() > 1) {
    for (std::size_t a = 0; a < out.size(); ++a) {
      out[a].set_name(std::string(kIdentifiedCaseName) + "_" + std::to_string(a + 1));
    }
  }
  return out;
}

// The first actuator's identified specimen, when its force channel contradicted the declared
// one and the fit has a storey model (a study holds one model for every storey).
std::optional<SpecimenModel> contradicted_specimen(const RunIdentification& run) {
  for (const auto& path : run.actuators) {
    if (!path.id.find(Channel::kMeasured)) continue;
    const RigModels rig = rig_models(path);
    if (!rig.specimen) continue;
    SpecimenModel model =
        specimen_model(*rig.specimen, signal_scales(identified_signals(path.id, Channel::kForce)));
    if (model.restoring_force) return model;
  }
  return std::nullopt;
}

}  // namespace

IdentifiedRun identified_run(const RunIdentification& run, const std::filesystem::path& base_dir,
                             const std::filesystem::path& trace_dir) {
  IdentifiedRun out;
  config::Study fragment;
  for (const auto& c :
       actuator_cases(run, study::case_named(run.study, run.case_name), out.notes)) {
    *fragment.add_cases() = c;
  }
  if (const auto specimen = contradicted_specimen(run)) {
    *fragment.mutable_substructuring()->mutable_model() = *specimen->restoring_force;
    out.notes.push_back("specimen: " + specimen->description +
                        " (the identified storey model; the structure keeps its stiffness)");
  }
  for (const auto& path : run.actuators)
    for (const auto& r : path.rejected)
      out.notes.push_back(r.part + ": " + r.effect + " left out: " +
                          (r.reason.empty()
                               ? "it made the re-run worse by " + percent_text(r.worsening) +
                                     " of the worst floor's NRMSE"
                               : r.reason));
  out.study = identified_study(run.study, base_dir, fragment);
  for (auto& node : *out.study.mutable_deployment()->mutable_nodes()) {
    if (node.kind() == config::NodeSpec::ACTUATOR_EMULATOR && fragment.cases_size() > 0) {
      node.clear_receive_delay();  // held by the identified case
    }
    if (node.kind() != config::NodeSpec::SUBSTRUCTURE) continue;
    for (const auto& link : run.links) {
      if (link.node_id != node.id()) continue;
      fit_link_lag(link, node);
      if (run.clock == "real_time") {
        node.add_receive_delay()->mutable_trace()->set_path(
            trace_path(trace_dir, link.node_id).string());
      }
    }
  }
  if (run.clock != "real_time") {
    out.notes.push_back(
        "links: a lockstep record's lag did not reach the response; the fitted "
        "receive_lag/send_lag apply to a real-time run");
  }
  return out;
}

std::vector<std::string> write_identified_run(const RunIdentification& run,
                                              const std::filesystem::path& base_dir,
                                              const std::filesystem::path& dir) {
  std::filesystem::create_directories(dir);
  std::vector<std::string> written;
  for (const auto& link : run.links) {
    const auto path = trace_path(dir, link.node_id);
    util::AtomicFile file(path);
    file.stream() << "# measured round trip of the link to node " << link.node_id
                  << ": time s, delay s\n";
    file.stream().precision(17);
    for (std::size_t i = 0; i < link.time.size(); ++i) {
      file.stream() << link.time[i] << "," << link.round_trip[i] << "\n";
    }
    file.commit();
    written.push_back("lag trace of the link to node " + std::to_string(link.node_id) + ": " +
                      path.string());
  }
  const IdentifiedRun identified = identified_run(run, base_dir, dir);
  std::vector<std::string> comment{
      "Identified by `rths identify " + run.record + "`: the run's own study with the identified",
      "actuator (case " + std::string(kIdentifiedCaseName) + ") and each link's measured lag.",
      "Run it: rths run " + (dir / "identified_run.textproto").string() + " (or rths launch)"};
  for (const auto& n : identified.notes) comment.push_back(n);
  const auto study_path = dir / "identified_run.textproto";
  study::write_text_format(identified.study, study_path, comment);
  written.push_back("study with the identified links and actuators (rths run, rths launch): " +
                    study_path.string());
  return written;
}

}  // namespace rths::identify
