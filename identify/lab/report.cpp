#include "identify/lab/report.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "identify/fit/effect_parameters.h"
#include "identify/fit/evidence.h"

namespace rths::identify {
namespace {

nlohmann::json params_json(const FitResult& fit, const SignalScales& scales) {
  nlohmann::json out = nlohmann::json::object();
  const auto specs = fit.model.specs(scales);
  for (std::size_t i = 0; i < specs.size(); ++i) {
    out[specs[i].name] = {{"value", fit.model.params[i]},
                          {"std_error", i < fit.std_errors.size() ? fit.std_errors[i] : 0.0},
                          {"unit", specs[i].unit}};
  }
  return out;
}

// Parameters belonging to one effect of the model (for a step's `params`).
nlohmann::json effect_params_json(const FitResult& fit, Effect effect, const SignalScales& scales) {
  nlohmann::json out = nlohmann::json::object();
  std::size_t index = base_params(fit.model.channel, scales).size();
  for (Effect e : fit.model.effects) {
    const auto specs = effect_params(e, fit.model.channel, scales);
    if (e == effect) {
      for (std::size_t i = 0; i < specs.size(); ++i) {
        out[specs[i].name] = {{"value", fit.model.params[index + i]},
                              {"std_error", fit.std_errors.at(index + i)},
                              {"unit", specs[i].unit}};
      }
    }
    index += specs.size();
  }
  return out;
}

nlohmann::json evidence_json(const Evidence& e) {
  return {{"residual_rms", e.residual_rms},
          {"corr_residual_displacement", e.corr_input},
          {"corr_residual_velocity", e.corr_velocity},
          {"corr_residual_velocity_sign", e.corr_velocity_sign},
          {"corr_residual_displacement_cubed", e.corr_input_cubed},
          {"corr_residual_acceleration", e.corr_acceleration},
          {"xcorr_input_residual_peak", e.input_to_residual.peak},
          {"xcorr_input_residual_lag_s", e.input_to_residual.lag},
          {"residual_dominant_frequency_hz", e.dominant_frequency},
          {"residual_power_below_1hz", e.low_frequency_share}};
}

nlohmann::json ranking_json(const std::vector<CandidateTrial>& ranking) {
  nlohmann::json out = nlohmann::json::array();
  for (const auto& t : ranking) {
    out.push_back({{"effect", effect_name(t.effect)},
                   {"added_params", t.added_params},
                   {"train_error", t.train_error},
                   {"heldout_error", t.heldout_error},
                   {"score", t.score},
                   {"pays", t.pays}});
  }
  return out;
}

nlohmann::json bound_hits_json(const std::vector<BoundHit>& hits) {
  nlohmann::json out = nlohmann::json::array();
  for (const auto& h : hits) {
    out.push_back({{"param", h.name},
                   {"bound", h.at_lower ? "lower" : "upper"},
                   {"value", h.bound},
                   {"message", h.message()}});
  }
  return out;
}

nlohmann::json model_json(const FitResult& fit, const SignalScales& scales) {
  nlohmann::json effects = nlohmann::json::array();
  for (Effect e : fit.model.effects) effects.push_back(effect_name(e));
  return {{"effects", effects},
          {"params", params_json(fit, scales)},
          {"train_error", fit.train_error},
          {"heldout_error", fit.heldout_error},
          {"bound_hits", bound_hits_json(fit.bound_hits)}};
}

nlohmann::json kind_json(const KindProposal& kind) {
  nlohmann::json ranking = nlohmann::json::array();
  for (const auto& k : kind.ranking) {
    ranking.push_back({{"kind", kind_name(k.kind)},
                       {"heldout_error", k.fit.heldout_error},
                       {"score", k.score},
                       {"physical", k.physical},
                       {"bound_hits", bound_hits_json(k.fit.bound_hits)}});
  }
  nlohmann::json out = {{"declared_bound_hits", bound_hits_json(kind.declared_hits)},
                        {"ranking", ranking}};
  out["proposed"] = kind.proposed ? nlohmann::json(kind_name(*kind.proposed)) : nlohmann::json();
  out["hysteretic_damper"] = kind.proposed && is_hysteretic_damper(*kind.proposed);
  return out;
}

nlohmann::json case_json(const CaseError& c) {
  return {{"name", c.name},
          {"nominal_delay_s", c.nominal_delay},
          {"peak_error_pct", c.peak_error_pct},
          {"rms_error_pct", c.rms_error_pct},
          {"paper_nrmse", c.nrmse},
          {"paper_eq2", c.paper_eq2},
          {"peak_displacement_m", c.peak_displacement},
          {"diverged", c.diverged}};
}

// The identified lag against the planned test's critical delay, as every pre-run check says it,
// and the lag the test could take.
std::string predicted_verdict(const core::CriticalDelayCheck& check) {
  std::string text = check.describe();
  if (const auto critical = check.critical()) {
    text += "; the test could take up to " + format_value(*critical * 1e3) + " ms";
    if (check.past()) text += ": expect it to diverge without compensation (--design-compensator)";
  }
  return text;
}

std::string percent(double v) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.2f %%", 100.0 * v);
  return buffer;
}

nlohmann::json step_json(const SelectionStep& s, const SignalScales& scales) {
  return {{"channel", channel_name(s.channel)},
          {"effect", effect_name(s.effect)},
          {"params", effect_params_json(s.after, s.effect, scales)},
          {"all_params", params_json(s.after, scales)},
          {"train_error_before", s.before.train_error},
          {"train_error_after", s.after.train_error},
          {"heldout_error_before", s.before.heldout_error},
          {"heldout_error_after", s.after.heldout_error},
          {"own_error_removed", s.own_error_removed},
          {"own_share", s.own_share},
          {"evidence", evidence_json(s.evidence_before)},
          {"ranking", ranking_json(s.ranking)}};
}

nlohmann::json channel_json(const Identification& id, const ChannelIdentification& c,
                            const SignalScales& scales) {
  nlohmann::json declared = nlohmann::json::array();
  for (Effect e : c.declared) declared.push_back(effect_name(e));
  nlohmann::json dropped = nlohmann::json::array();
  for (const auto& s : c.dropped_at_full_rate) {
    dropped.push_back({{"effect", effect_name(s.effect)},
                       {"heldout_error_before", s.before.heldout_error},
                       {"heldout_error_after", s.after.heldout_error}});
  }
  return {{"channel", channel_name(c.channel)},
          {"declared_effects", declared},
          {"declared", model_json(c.declared_fit, scales)},
          {"start", model_json(c.start_fit, scales)},
          {"kind", c.kind ? kind_json(*c.kind) : nlohmann::json()},
          {"noise_floor", c.noise_floor},
          // model.h make_signals: the specimen's input low-pass (0: none).
          {"input_lowpass_hz", identified_signals(id, c.channel).input_cutoff},
          {"final", model_json(c.final_fit, scales)},
          {"final_evidence", evidence_json(c.final_evidence)},
          {"search_heldout_error", c.search_heldout_error},
          {"dropped_at_full_rate", dropped},
          {"rejected", ranking_json(c.last_ranking)}};
}

nlohmann::json prediction_json(const StudyPrediction& prediction) {
  nlohmann::json cases = nlohmann::json::array();
  for (const auto& c : prediction.cases) cases.push_back(case_json(c));
  nlohmann::json out = {{"config", prediction.config},
                        {"reference_case", prediction.reference_case},
                        {"dt", prediction.dt},
                        {"actuator", prediction.actuator},
                        {"ignored", prediction.ignored},
                        {"identified", case_json(prediction.identified)},
                        {"cases", cases}};
  if (const auto& st = prediction.stability) {
    const auto critical = st->critical();
    out["stability"] = {
        {"lag_s", st->lag},
        {"critical_delay_s", critical ? nlohmann::json(*critical) : nlohmann::json(nullptr)},
        {"margin", critical ? nlohmann::json(st->margin()) : nlohmann::json(nullptr)},
        {"past", st->past()},
        {"verdict", predicted_verdict(*st)}};
  }
  return out;
}

void write_channel_header(std::ostringstream& out, const Identification& id,
                          const ChannelIdentification& c) {
  out << "channel " << channel_name(c.channel) << ": declared model {";
  for (std::size_t i = 0; i < c.declared.size(); ++i) {
    out << (i ? ", " : "") << effect_name(c.declared[i]);
  }
  out << "}  train " << percent(c.declared_fit.train_error) << ", held-out "
      << percent(c.declared_fit.heldout_error) << "\n";
  out << "  noise floor (estimated from the record): " << percent(c.noise_floor) << "\n";
  if (const double cutoff = identified_signals(id, c.channel).input_cutoff; cutoff > 0.0) {
    out << "  the model runs on the measured displacement low-passed at " << format_value(cutoff)
        << " Hz (zero phase)\n";
  }
  for (const auto& hit : c.declared_fit.bound_hits) {
    out << "  declared fit ends at a bound: " << hit.message()
        << (c.kind ? ": the declared model is the wrong kind" : "") << "\n";
  }
}

// The specimen-kind search: the ranking of the library's kinds and the one the search starts from.
void write_kind_search(std::ostringstream& out, const ChannelIdentification& c) {
  if (c.kind) {
    out << "  specimen kinds (held-out at the search rate):";
    for (const auto& k : c.kind->ranking) {
      out << " " << kind_name(k.kind) << " " << percent(k.fit.heldout_error)
          << (k.physical ? "" : " (wrong kind: at a bound)") << ";";
    }
    out << "\n";
    if (c.kind->proposed) {
      out << "  proposed kind: " << kind_name(*c.kind->proposed)
          << (is_hysteretic_damper(*c.kind->proposed) ? " (a damper with hysteresis)" : "")
          << "; the search starts from it: held-out " << percent(c.start_fit.heldout_error) << "\n";
    } else {
      out << "  no kind of the library fits without reaching a bound\n";
    }
  }
}

void write_step(std::ostringstream& out, const SelectionStep& s, int n,
                const SignalScales& scales) {
  out << "  step " << n << ": + " << effect_name(s.effect) << "   train "
      << percent(s.before.train_error) << " -> " << percent(s.after.train_error) << "   held-out "
      << percent(s.before.heldout_error) << " -> " << percent(s.after.heldout_error) << "\n";
  const auto p = effect_params_json(s.after, s.effect, scales);
  for (auto it = p.begin(); it != p.end(); ++it) {
    out << "      " << it.key() << " = " << format_value(it.value()["value"]) << " +/- "
        << format_value(it.value()["std_error"]) << " " << it.value()["unit"].get<std::string>()
        << "\n";
  }
  const auto& e = s.evidence_before;
  out << "      evidence before: corr(res, disp) " << format_value(e.corr_input)
      << ", corr(res, vel) " << format_value(e.corr_velocity) << ", corr(res, sgn vel) "
      << format_value(e.corr_velocity_sign) << ", xcorr(input, res) "
      << format_value(e.input_to_residual.peak) << " at "
      << format_value(e.input_to_residual.lag * 1e3) << " ms, residual peak at "
      << format_value(e.dominant_frequency) << " Hz\n";
  out << "      ranking (held-out at the search rate):";
  for (std::size_t k = 0; k < std::min<std::size_t>(4, s.ranking.size()); ++k) {
    out << " " << effect_name(s.ranking[k].effect) << " " << percent(s.ranking[k].heldout_error)
        << (k + 1 < std::min<std::size_t>(4, s.ranking.size()) ? "," : "");
  }
  out << "\n";
}

void write_channel_outcome(std::ostringstream& out, const ChannelIdentification& c,
                           const SignalScales& scales) {
  for (const auto& d : c.dropped_at_full_rate) {
    out << "  dropped: + " << effect_name(d.effect) << " paid at the search rate but not at the "
        << "full rate (held-out " << percent(d.before.heldout_error) << " -> "
        << percent(d.after.heldout_error) << ")\n";
  }
  if (c.steps.size() > 1) {
    std::vector<const SelectionStep*> by_part;
    for (const auto& st : c.steps) by_part.push_back(&st);
    std::stable_sort(by_part.begin(), by_part.end(), [](const auto* a, const auto* b) {
      return a->own_error_removed > b->own_error_removed;
    });
    out << "  effects by their own part (held-out error lost when each is left out):";
    for (const auto* st : by_part) {
      out << " " << effect_name(st->effect) << " " << percent(st->own_error_removed) << " ("
          << format_value(100.0 * st->own_share) << " % of the parts);";
    }
    out << "\n";
  }
  out << "  final: " << c.final_fit.model.describe(scales) << "\n";
  out << "  final held-out " << percent(c.final_fit.heldout_error) << " = "
      << format_value(c.noise_floor > 0.0 ? c.final_fit.heldout_error / c.noise_floor : 0.0)
      << " x the noise floor\n";
  for (const auto& hit : c.final_fit.bound_hits) {
    out << "  final fit ends at a bound: " << hit.message() << "\n";
  }
  if (!c.last_ranking.empty()) {
    out << "  best rejected: " << effect_name(c.last_ranking.front().effect) << " (held-out "
        << percent(c.last_ranking.front().heldout_error) << " vs "
        << percent(c.search_heldout_error) << " without it, at the search rate)\n";
  }
}

void write_prediction(std::ostringstream& out, const StudyPrediction& prediction) {
  out << "prediction with " << prediction.config << " (reference case '"
      << prediction.reference_case << "', dt " << prediction.dt << " s)\n";
  out << "  identified actuator: " << prediction.actuator << "\n";
  for (const auto& ig : prediction.ignored) out << "  not transferred: " << ig << "\n";
  const auto line = [&](const CaseError& c) {
    out << "  " << c.name << ": nominal lag " << format_value(c.nominal_delay * 1e3)
        << " ms, E_peak " << percent(c.peak_error_pct / 100) << ", E_rms "
        << percent(c.rms_error_pct / 100) << ", peak " << format_value(c.peak_displacement * 1e3)
        << " mm (the paper's NRMSE " << percent(c.nrmse) << ", Eq. 2 " << format_value(c.paper_eq2)
        << ")" << (c.diverged ? " (DIVERGED)" : "") << "\n";
  };
  line(prediction.identified);
  for (const auto& c : prediction.cases) line(c);
  if (const auto& st = prediction.stability)
    out << "  before booking the lab: the identified actuator's " << predicted_verdict(*st) << "\n";
}

}  // namespace

std::string format_value(double v) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.4g", v);
  return buffer;
}

nlohmann::json to_json(const Identification& id, const ReportContext& context,
                       const std::optional<StudyPrediction>& prediction) {
  nlohmann::json out;
  out["source"] = id.source;
  out["samples"] = id.samples;
  out["dt"] = id.dt;
  out["search_decimation"] = id.search_decimation;
  out["holdout"] = {{"mode", context.holdout_mode == HoldoutMode::kLast ? "last" : "blocks"},
                    {"fraction", context.holdout_fraction},
                    {"train_samples", id.split.train.size()},
                    {"heldout_samples", id.split.heldout.size()}};
  nlohmann::json steps = nlohmann::json::array();
  nlohmann::json channels = nlohmann::json::array();
  for (const auto& c : id.channels) {
    const SignalScales scales = signal_scales(identified_signals(id, c.channel));
    for (const auto& s : c.steps) steps.push_back(step_json(s, scales));
    channels.push_back(channel_json(id, c, scales));
  }
  out["steps"] = steps;
  out["channels"] = channels;
  if (prediction) out["prediction"] = prediction_json(*prediction);
  return out;
}

std::string format_table(const Identification& id,
                         const std::optional<StudyPrediction>& prediction) {
  std::ostringstream out;
  out << "rths identify: " << id.source << " (" << id.samples << " samples, dt " << id.dt
      << " s; search decimated x" << id.search_decimation << ", errors at the full rate; "
      << id.split.train.size() << " training / " << id.split.heldout.size()
      << " held-out samples)\n";
  out << "error = RMS(residual) / std(measured signal)\n\n";
  for (const auto& c : id.channels) {
    const SignalScales scales = signal_scales(identified_signals(id, c.channel));
    write_channel_header(out, id, c);
    write_kind_search(out, c);
    if (c.steps.empty()) out << "  nothing added: no candidate pays on held-out data\n";
    int n = 1;
    for (const auto& s : c.steps) write_step(out, s, n++, scales);
    write_channel_outcome(out, c, scales);
    out << "\n";
  }
  if (prediction) write_prediction(out, *prediction);
  return out.str();
}

}  // namespace rths::identify
