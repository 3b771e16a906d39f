#include "identify/run/run_record_format.h"

#include <sstream>

#include "core/number_text.h"
#include "identify/run/findings.h"
#include "identify/run/response_floor.h"

namespace rths::identify {
namespace {

void link_text(const NetworkPath& l, std::ostream& out) {
  out << "link to node " << l.node_id << ": " << l.answers << " answers; round trip beyond the"
      << " injected lag: bias " << l.bias * 1e3 << " ms, jitter " << l.jitter * 1e3
      << " ms, drift over the run " << l.drift_range * 1e3 << " ms; " << l.spikes
      << " spikes; lost " << l.lost << " (longest burst " << l.longest_burst << "), superseded "
      << l.superseded << ", late " << l.late << "; injected " << l.injected_mean * 1e3
      << " ms (declared " << l.declared.round_trip * 1e3 << " ms)\n";
  if (l.effects.empty()) out << "  undeclared effects: none\n";
  for (const auto& e : l.effects) {
    out << "  undeclared: " << e.name << ": " << e.detail;
    if (e.heldout_before > 0.0) {
      out << " (held-out RMS " << e.heldout_before * 1e3 << " -> " << e.heldout_after * 1e3
          << " ms, held-out share " << percent_text(e.share) << ")";
    }
    out << "\n";
  }
}

// The sensors' noise (RMS, as estimated and as declared) and the displacement sensor's scale.
void sensors_text(const ActuatorPath& a, std::ostream& out) {
  const auto precision = out.precision(3);
  out << "  sensors: displacement noise " << a.displacement_noise * 1e3 << " mm RMS (declared "
      << a.declared_displacement_noise * 1e3 << " mm), load cell noise " << a.force_noise
      << " N RMS (declared " << a.declared_force_noise << " N)";
  if (a.displacement_scale != 1.0)
    out << ", displacement sensor scale " << a.displacement_scale << " +/- "
        << a.displacement_scale_error;
  out << "\n";
  out.precision(precision);
}

void actuator_text(const ActuatorPath& a, std::ostream& out) {
  out << "actuator " << a.actuator << ": declared";
  for (const auto& d : a.declared) out << " " << d << ",";
  out << " gain " << a.declared_gain << " (fitted " << a.fitted_gain << ")";
  if (a.delay_declared)
    out << ", delay " << a.declared_delay * 1e3 << " ms (fitted " << a.fitted_delay * 1e3 << " ms)";
  out << "\n";
  for (const auto& c : a.id.channels) {
    out << "  " << channel_name(c.channel) << ": held-out "
        << percent_text(c.declared_fit.heldout_error) << " declared -> "
        << percent_text(c.final_fit.heldout_error) << " identified";
    for (const auto& e : a.estimates)
      if (e.channel == c.channel && e.added)
        out << "; + " << effect_name(e.effect)
            << (e.share ? " (held-out share " + percent_text(*e.share) + ")" : "");
    out << "\n";
    for (const auto& e : a.estimates)
      if (e.channel == c.channel && e.added)
        for (const ParameterEstimate& p : e.parameters)
          out << "    " << effect_name(e.effect) << ": " << p.describe() << "\n";
  }
  out << "  undeclared effects: ";
  for (std::size_t i = 0; i < a.undeclared.size(); ++i) out << (i ? ", " : "") << a.undeclared[i];
  out << (a.undeclared.empty() ? "none\n" : "\n");
  if (!a.not_named.empty()) {
    out << "  described, not named (the description beat the fit held out):";
    for (std::size_t i = 0; i < a.not_named.size(); ++i)
      out << (i ? ", " : " ") << a.not_named[i].effect << " ("
          << channel_name(a.not_named[i].channel) << ")";
    out << "\n";
  }
  if (!a.delay_by_direction.empty()) out << "  delay: " << a.delay_by_direction << "\n";
  for (const auto& held : a.held_not_named)
    out << "  held, not named (" << channel_name(held.channel) << "): " << held.why << "\n";
  sensors_text(a, out);
  if (a.declared_specimen.empty()) return;
  out << "  specimen: declared";
  for (const auto& d : a.declared_specimen) out << " " << d;
  if (a.declared_stiffness > 0.0) out << ", stiffness " << a.declared_stiffness << " N/m";
  out << " (fitted " << a.fitted_stiffness << " N/m); undeclared: ";
  for (std::size_t i = 0; i < a.specimen_undeclared.size(); ++i)
    out << (i ? ", " : "") << a.specimen_undeclared[i];
  out << (a.specimen_undeclared.empty() ? "none\n" : "\n");
}

void residual_text(const RunResidual& r, std::ostream& out) {
  out << "response re-run in process over " << r.steps << " steps, NRMSE against the record "
      << "(declared -> identified):";
  for (const auto& f : r.floors) {
    out << " floor " << f.dof << " " << percent_text(f.declared) << " -> "
        << percent_text(f.identified) << ";";
  }
  out << (r.declared_diverged ? " the declared model diverges;" : "")
      << (r.identified_diverged ? " the identified model diverges;" : "") << "\n";
  for (const auto* kind : {&r.links, &r.effects}) {
    for (const auto& s : *kind) {
      out << "  " << s.link << (s.effect == "all" ? "" : ": " + s.effect) << " removes "
          << percent_text(s.removed) << " of NRMSE from the worst floor (share "
          << percent_text(s.share) << ")\n";
    }
  }
  for (const auto& m : r.moving) {
    const MovingParameter& p = m.parameter;
    out << "  " << p.part << ": " << p.effect << " moving (" << shape_name(p.shape.shape) << ", "
        << core::format_number(p.shape.start) << " -> " << core::format_number(p.shape.end)
        << (p.unit.empty() ? "" : " " + p.unit) << "): held-out NRMSE " << percent_text(m.constant)
        << " with its constant " << core::format_number(p.constant) << ", "
        << percent_text(m.moving) << " moving (chosen on these held-out steps): "
        << (m.kept ? "held moving" : "held constant (moving does not help)") << "\n";
  }
  for (const auto& n : r.notes) out << "  note: " << n << "\n";
}

// The moving parameters tried in the re-run (run_residual.h moving).
nlohmann::json moving_json(const std::vector<MovingRerun>& moving) {
  nlohmann::json out = nlohmann::json::array();
  for (const auto& m : moving)
    out.push_back({{"part", m.parameter.part},
                   {"effect", m.parameter.effect},
                   {"shape", shape_name(m.parameter.shape.shape)},
                   {"start", m.parameter.shape.start},
                   {"end", m.parameter.shape.end},
                   {"at_s", m.parameter.shape.at},
                   {"unit", m.parameter.unit},
                   {"constant", m.parameter.constant},
                   {"heldout_nrmse_constant", m.constant},
                   {"heldout_nrmse_moving", m.moving},
                   // the held-out NRMSEs above are the steps `kept` was decided on
                   {"chosen_on_heldout", true},
                   {"kept", m.kept}});
  return out;
}

// The effects the re-run rejected (ActuatorPath::rejected), one line each; empty when none.
std::string rejected_text(const std::vector<ActuatorPath>& paths) {
  std::ostringstream out;
  for (const auto& a : paths)
    for (const auto& r : a.rejected) {
      out << "  " << r.part << ": " << r.effect << " rejected: ";
      if (r.reason.empty())
        out << "makes the re-run's NRMSE worse by " << percent_text(r.worsening)
            << " (worst floor)\n";
      else
        out << r.reason << "\n";
    }
  const std::string lines = out.str();
  if (lines.empty()) return lines;
  return "rejected, named by a channel but made the re-run worse or fitted badly (left out of it "
         "and of the written study):\n" +
         lines;
}

nlohmann::json rejected_json(const std::vector<ActuatorPath>& paths) {
  nlohmann::json out = nlohmann::json::array();
  for (const auto& a : paths)
    for (const auto& r : a.rejected)
      out.push_back({{"part", r.part},
                     {"effect", r.effect},
                     {"channel", channel_name(r.channel)},
                     {"nrmse_added", r.worsening},
                     {"reason", r.reason}});
  return out;
}

nlohmann::json residual_json(const RunResidual& r) {
  nlohmann::json floors = nlohmann::json::array(), links = nlohmann::json::array(),
                 effects = nlohmann::json::array();
  for (const auto& f : r.floors) {
    floors.push_back(
        {{"dof", f.dof}, {"declared_nrmse", f.declared}, {"identified_nrmse", f.identified}});
  }
  for (const auto& [kind, list] : {std::pair{&r.links, &links}, std::pair{&r.effects, &effects}}) {
    for (const auto& s : *kind) {
      list->push_back({{"link", s.link},
                       {"effect", s.effect},
                       {"nrmse_removed", s.removed},
                       {"share", s.share}});
    }
  }
  return {{"steps", r.steps},
          {"floors", floors},
          {"declared_nrmse", r.declared},
          {"identified_nrmse", r.identified},
          {"declared_diverged", r.declared_diverged},
          {"identified_diverged", r.identified_diverged},
          {"links", links},
          {"effects", effects},
          {"moving", moving_json(r.moving)},
          {"notes", r.notes}};
}

nlohmann::json links_json(const RunIdentification& run) {
  nlohmann::json links = nlohmann::json::array();
  for (const auto& l : run.links) {
    nlohmann::json effects = nlohmann::json::array();
    for (const auto& e : l.effects) {
      effects.push_back({{"name", e.name},
                         {"detail", e.detail},
                         {"heldout_rms_before_s", e.heldout_before},
                         {"heldout_rms_after_s", e.heldout_after},
                         {"heldout_share", e.share}});
    }
    links.push_back(
        {{"node_id", l.node_id},
         {"answers", l.answers},
         {"bias_s", l.bias},
         {"jitter_s", l.jitter},
         {"drift_range_s", l.drift_range},
         {"spikes", l.spikes},
         {"spike_period_s", l.spike_period},
         {"lost", l.lost},
         {"longest_burst", l.longest_burst},
         {"superseded", l.superseded},
         {"late", l.late},
         {"injected_mean_s", l.injected_mean},
         {"declared_round_trip_s", l.declared.round_trip},
         {"clock_offset_s", l.clock ? nlohmann::json(l.clock->offset) : nlohmann::json()},
         {"heldout_rms_declared_s", l.heldout_declared},
         {"undeclared", effects}});
  }
  return links;
}

// The effects the description beat (unexplained.h judge_named): [{channel, effect}].
nlohmann::json not_named_json(const ActuatorPath& a) {
  nlohmann::json out = nlohmann::json::array();
  for (const auto& n : a.not_named)
    out.push_back({{"channel", channel_name(n.channel)}, {"effect", n.effect}});
  return out;
}

// The effects held in the re-run but not named (ActuatorPath::held_not_named): [{channel, effect,
// why}].
nlohmann::json held_json(const ActuatorPath& a) {
  nlohmann::json out = nlohmann::json::array();
  for (const auto& h : a.held_not_named)
    out.push_back({{"channel", channel_name(h.channel)}, {"effect", h.effect}, {"why", h.why}});
  return out;
}

nlohmann::json actuators_json(const RunIdentification& run) {
  nlohmann::json actuators = nlohmann::json::array();
  for (const auto& a : run.actuators) {
    nlohmann::json channels = nlohmann::json::array();
    for (const auto& c : a.id.channels) {
      nlohmann::json effects = nlohmann::json::array();
      for (const auto& e : a.estimates)
        if (e.channel == c.channel && e.added)
          effects.push_back(
              {{"effect", effect_name(e.effect)},
               {"heldout_share", e.share ? nlohmann::json(*e.share) : nlohmann::json()},
               {"parameters", parameters_json(e.parameters)}});
      channels.push_back({{"channel", channel_name(c.channel)},
                          {"declared_heldout_error", c.declared_fit.heldout_error},
                          {"identified_heldout_error", c.final_fit.heldout_error},
                          {"effects", effects}});
    }
    actuators.push_back(
        {{"actuator", a.actuator},
         {"declared", a.declared},
         {"declared_gain", a.declared_gain},
         {"fitted_gain", a.fitted_gain},
         {"delay_declared", a.delay_declared},
         {"declared_delay_s", a.declared_delay},
         {"fitted_delay_s", a.fitted_delay},
         {"channels", channels},
         {"undeclared", a.undeclared},
         {"declared_specimen", a.declared_specimen},
         {"declared_stiffness_n_per_m", a.declared_stiffness},
         {"fitted_stiffness_n_per_m", a.fitted_stiffness},
         {"specimen_undeclared", a.specimen_undeclared},
         {"not_named", not_named_json(a)},
         {"held_not_named", held_json(a)},
         {"delay_by_direction",
          a.delay_by_direction.empty() ? nlohmann::json() : nlohmann::json(a.delay_by_direction)},
         {"sensors",
          {{"displacement_noise_m", a.displacement_noise},
           {"declared_displacement_noise_m", a.declared_displacement_noise},
           {"force_noise_n", a.force_noise},
           {"declared_force_noise_n", a.declared_force_noise},
           {"displacement_scale", a.displacement_scale},
           {"displacement_scale_std_error", a.displacement_scale_error}}}});
  }
  return actuators;
}

}  // namespace

std::string run_record_text(const RunIdentification& run) {
  std::ostringstream out;
  out << "record " << run.record << ": case '" << run.case_name << "', " << run.clock << ", "
      << run.held << "; " << run.steps << " steps (" << run.duration << " s) identified\n";
  out << "inputs: " << run.inputs << "\n";
  if (run.platform && run.platform->overruns > 0)
    out << "platform: " << run.platform->overruns << " of " << run.platform->steps
        << " steps overran their deadline (" << run.platform->cause
        << "); the record: " << run.platform->usability << "\n";
  if (run.platform && run.platform->verdict)
    out << "real-time verdict: " << *run.platform->verdict << "\n";
  if (run.replay && run.replay->late_steps > 0)
    out << "answers the loop used: " << run.replay->text()
        << "; the rig is identified on each answer at its own step, the re-run replays them\n";
  for (const auto& l : run.links) link_text(l, out);
  for (const auto& a : run.actuators) actuator_text(a, out);
  if (run.residual) residual_text(*run.residual, out);
  out << findings_text(run.findings, run.residual ? &*run.residual : nullptr);
  out << rejected_text(run.actuators);
  out << unexplained_section(run.unexplained, run.floors);
  if (const auto floor = response_floor(run)) out << "  " << floor->text() << "\n";
  return out.str();
}

nlohmann::json run_record_json(const RunIdentification& run) {
  const nlohmann::json links = links_json(run), actuators = actuators_json(run);
  nlohmann::json out = {
      {"record", run.record},       {"case", run.case_name}, {"clock", run.clock},
      {"held", run.held},           {"inputs", run.inputs},  {"steps", run.steps},
      {"duration_s", run.duration}, {"links", links},        {"actuators", actuators}};
  if (run.residual) out["residual"] = residual_json(*run.residual);
  out["undeclared"] = findings_json(run.findings);
  out["rejected"] = rejected_json(run.actuators);
  out["unexplained"] = unexplained_json(run.unexplained, run.floors);
  out["residual_floor"] = json_array(run.floors);
  if (const auto floor = response_floor(run)) {
    out["response_floor"] = floor->json();
    if (const nlohmann::json entry = floor->unexplained_json(); !entry.is_null())
      out["unexplained"].push_back(entry);
  }
  if (const auto& p = run.platform)
    out["platform"] = {
        {"steps", p->steps},
        {"overruns", p->overruns},
        {"overrun_share", p->overrun_share()},
        {"dominated_by_overruns", p->overrun_share() > runtime::DeadlineDiagnosis::kDominatedShare},
        {"worst_streak", p->worst_streak},
        {"cause", p->cause},
        {"usability", p->usability},
        {"verdict", p->verdict ? nlohmann::json(*p->verdict) : nlohmann::json()}};
  if (const auto& r = run.replay)
    out["answers_used"] = {{"late_steps", r->late_steps},
                           {"mean_age_steps", r->mean_age},
                           {"oldest_steps", r->oldest},
                           {"replayed", r->late_steps > 0}};
  return out;
}

}  // namespace rths::identify
