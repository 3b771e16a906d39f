#include "identify/fit/selection.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>

namespace rths::identify {
namespace {

std::vector<std::vector<double>> guess_grid(const std::vector<ParamSpec>& specs) {
  std::vector<std::vector<double>> grid{{}};
  for (const auto& spec : specs) {
    std::vector<std::vector<double>> next;
    for (const auto& partial : grid) {
      for (double g : spec.guesses) {
        auto extended = partial;
        extended.push_back(g);
        next.push_back(std::move(extended));
      }
    }
    grid = std::move(next);
  }
  return grid;
}

}  // namespace

std::vector<Effect> default_declared(Channel channel) {
  if (channel == Channel::kMeasured) return {Effect::kDelay};
  return {Effect::kStiffness};
}

FitResult fit_with_effect(const ChannelModel& model, Effect effect, const ChannelSignals& signals,
                          const Split& split, const FitOptions& options) {
  const SignalScales sc = signal_scales(signals);
  auto specs = declared_specs(effect_params(effect, model.channel, sc), model.declarations);
  const bool declared_start =
      std::any_of(model.declarations.begin(), model.declarations.end(),
                  [&](const ParamDeclaration& d) { return d.name == specs[0].name && d.initial; });
  if (effect == Effect::kDelay && !declared_start) {
    // The lag of the target behind the input by cross-correlation is the natural first guess.
    const auto xc = cross_correlation(signals.input, signals.target, signals.dt, 0.25);
    specs[0].guesses.insert(specs[0].guesses.begin(),
                            std::clamp(xc.lag, specs[0].lower, specs[0].upper));
    if (model.channel == Channel::kForce) specs[0].guesses = {0.0, 0.002};
  }
  FitResult best;
  double best_cost = std::numeric_limits<double>::infinity();
  for (const auto& guess : guess_grid(specs)) {
    const ChannelModel start = with_effect(model, effect, guess);
    FitResult fit = fit_channel(start, signals, split, options);
    if (std::isfinite(fit.cost) && fit.cost < best_cost) {
      best_cost = fit.cost;
      best = std::move(fit);
    }
  }
  if (!std::isfinite(best_cost))
    best = evaluate_channel(with_effect(model, effect, guess_grid(specs)[0]), signals, split);
  return best;
}

namespace {

// Every declared effect at once, each at its first guess (its declared value where the config
// gives one), fitted jointly; nullopt when no effect has a declared value.
std::optional<FitResult> joint_declared_fit(const ChannelModel& base,
                                            const std::vector<Effect>& declared,
                                            const ChannelSignals& signals, const Split& split,
                                            const FitOptions& options) {
  const SignalScales sc = signal_scales(signals);
  ChannelModel model = base;
  bool any_declared_value = false;
  for (Effect e : declared) {
    if (!effect_applies(e, signals.channel) || model.has(e)) continue;
    const auto specs = declared_specs(effect_params(e, model.channel, sc), model.declarations);
    for (const auto& spec : specs)
      for (const auto& d : model.declarations)
        any_declared_value |= d.name == spec.name && d.initial;
    model = with_effect(model, e, guess_grid(specs)[0]);
  }
  if (!any_declared_value) return std::nullopt;
  return fit_channel(model, signals, split, options);
}

}  // namespace

// The declared effects added one at a time, each fitted with those before it; and, where the
// config gives values, all of them at those values fitted jointly: one at a time, a delay fitted
// alone takes up the lag of a first order or a velocity limit declared after it, and the joint
// fit then starts from another minimum. The lower cost stands.
ChannelModel fit_declared(const ChannelSignals& signals, const Split& split,
                          const std::vector<Effect>& declared, const FitOptions& options,
                          const std::vector<ParamDeclaration>& declarations) {
  const SignalScales sc = signal_scales(signals);
  ChannelModel model = declared_model(signals.channel, {}, sc);
  model.declarations = declarations;
  const auto base = model.specs(sc);
  for (std::size_t i = 0; i < base.size(); ++i) model.params[i] = base[i].guesses.at(0);
  const std::optional<FitResult> joint =
      joint_declared_fit(model, declared, signals, split, options);
  double cost = std::numeric_limits<double>::infinity();
  for (Effect e : declared) {
    if (!effect_applies(e, signals.channel) || model.has(e)) continue;
    FitResult fit = fit_with_effect(model, e, signals, split, options);
    model = std::move(fit.model);
    cost = fit.cost;
  }
  if (joint && std::isfinite(joint->cost) && joint->cost < cost) return joint->model;
  return model;
}

KindProposal compare_kinds(const ChannelSignals& signals, const Split& split,
                           const std::vector<BoundHit>& declared_hits,
                           const SelectionOptions& options,
                           const std::vector<ParamDeclaration>& declarations) {
  if (signals.channel != Channel::kForce) {
    throw std::invalid_argument("compare_kinds: specimen kinds apply to the force channel only");
  }
  KindProposal proposal;
  proposal.declared_hits = declared_hits;
  for (SpecimenKind kind : specimen_kinds()) {
    if (options.stage) options.stage("specimen kind " + kind_name(kind));
    KindTrial trial;
    trial.kind = kind;
    auto effects = kind_effects(kind);
    effects.push_back(Effect::kOffsetDrift);
    trial.fit = fit_channel(fit_declared(signals, split, effects, options.fit, declarations),
                            signals, split, options.fit);
    trial.score =
        trial.fit.heldout_error *
        (1.0 + options.penalty_per_parameter * static_cast<double>(trial.fit.model.params.size()));
    const auto defining = defining_effects(kind);
    const SignalScales scales = signal_scales(signals);
    for (const auto& hit : trial.fit.bound_hits) {
      const auto owner = trial.fit.model.effect_of(hit.index, scales);
      if (owner && std::find(defining.begin(), defining.end(), *owner) != defining.end()) {
        trial.physical = false;
      }
    }
    proposal.ranking.push_back(std::move(trial));
    if (options.progress) options.progress(proposal.ranking.size());
  }
  std::stable_sort(proposal.ranking.begin(), proposal.ranking.end(),
                   [](const KindTrial& a, const KindTrial& b) {
                     if (a.physical != b.physical) return a.physical;
                     return a.score < b.score;
                   });
  if (proposal.ranking.front().physical) proposal.proposed = proposal.ranking.front().kind;
  return proposal;
}

namespace {

// The candidates of the pool that apply to the channel (P of selection_units).
std::size_t pool_units(const SelectionOptions& options, Channel channel) {
  const std::vector<Effect> pool =
      options.candidates.empty() ? effect_library(channel) : options.candidates;
  std::size_t count = 0;
  for (Effect e : pool) count += effect_applies(e, channel) ? 1 : 0;
  return std::max<std::size_t>(1, count);
}

bool proposes_kind(const SelectionOptions& options, Channel channel) {
  return options.propose_kind && channel == Channel::kForce;
}

// Reports `units` through options.progress, never less than what was reported before.
class ProgressUnits {
 public:
  explicit ProgressUnits(const SelectionOptions& options) : options_(options) {}
  void report(std::size_t units) {
    reported_ = std::max(reported_, units);
    if (options_.progress) options_.progress(reported_);
  }
  std::size_t reported() const { return reported_; }

 private:
  const SelectionOptions& options_;
  std::size_t reported_ = 0;
};

// Greedy forward selection from `start`: fills steps, last_ranking and final_fit of `id`. The
// search's progress units run from `first_unit` to first_unit + max_steps x P.
void search_from(ChannelIdentification& id, const FitResult& start, const ChannelSignals& signals,
                 const Split& split, const SelectionOptions& options, ProgressUnits& progress,
                 std::size_t first_unit) {
  id.start_fit = start;
  id.steps.clear();
  id.last_ranking.clear();
  FitResult current = start;
  const SignalScales sc = signal_scales(signals);
  const std::vector<Effect> pool =
      options.candidates.empty() ? effect_library(signals.channel) : options.candidates;
  const std::size_t per_round = pool_units(options, signals.channel);
  for (std::size_t round = 0; round < options.max_steps; ++round) {
    std::vector<CandidateTrial> trials;
    std::size_t in_round = 0;
    for (Effect e : pool) {
      in_round += effect_applies(e, signals.channel) && !current.model.has(e) ? 1 : 0;
    }
    for (Effect e : pool) {
      if (!effect_applies(e, signals.channel) || current.model.has(e)) continue;
      if (options.stage) {
        options.stage("candidate " + effect_name(e) + " (round " + std::to_string(round + 1) + ")");
      }
      CandidateTrial trial;
      trial.effect = e;
      trial.added_params = effect_params(e, signals.channel, sc).size();
      trial.fit = fit_with_effect(current.model, e, signals, split, options.fit);
      trial.train_error = trial.fit.train_error;
      trial.heldout_error = trial.fit.heldout_error;
      trial.score = trial.heldout_error *
                    (1.0 + options.penalty_per_parameter * static_cast<double>(trial.added_params));
      trial.pays =
          trial.heldout_error <= (1.0 - options.min_relative_improvement) * current.heldout_error &&
          trial.score < current.heldout_error;
      trials.push_back(std::move(trial));
      progress.report(first_unit + round * per_round + trials.size() * per_round / in_round);
    }
    std::sort(trials.begin(), trials.end(),
              [](const CandidateTrial& a, const CandidateTrial& b) { return a.score < b.score; });
    if (trials.empty() || !trials.front().pays) {
      id.last_ranking = std::move(trials);
      break;
    }
    SelectionStep step;
    step.channel = signals.channel;
    step.effect = trials.front().effect;
    step.before = current;
    step.evidence_before = residual_evidence(signals, current.prediction);
    step.after = trials.front().fit;
    current = step.after;
    step.ranking = std::move(trials);
    id.steps.push_back(std::move(step));
  }
  id.final_fit = current;
  progress.report(first_unit + options.max_steps * per_round);
}

}  // namespace

std::size_t selection_units(const SelectionOptions& options, Channel channel) {
  const std::size_t search = options.max_steps * pool_units(options, channel);
  return 1 + search + (proposes_kind(options, channel) ? specimen_kinds().size() + search : 0);
}

void attribute_shares(ChannelIdentification& id, const ChannelSignals& signals, const Split& split,
                      const FitOptions& options) {
  const SignalScales scales = signal_scales(signals);
  double total = 0.0;
  for (auto& step : id.steps) {
    const FitResult without = fit_channel(without_effect(id.final_fit.model, step.effect, scales),
                                          signals, split, options);
    step.own_error_removed = std::max(0.0, without.heldout_error - id.final_fit.heldout_error);
    total += step.own_error_removed;
  }
  for (auto& step : id.steps) step.own_share = total > 0.0 ? step.own_error_removed / total : 0.0;
}

ChannelIdentification identify_channel(const ChannelSignals& signals, const Split& split,
                                       const std::vector<Effect>& declared,
                                       const SelectionOptions& options,
                                       const std::vector<ParamDeclaration>& declarations) {
  ChannelIdentification id;
  id.channel = signals.channel;
  id.declared = declared;
  ProgressUnits progress(options);
  const std::size_t search_units = options.max_steps * pool_units(options, signals.channel);
  if (options.stage) options.stage("declared model");
  const ChannelModel declared_fit =
      fit_declared(signals, split, declared, options.fit, declarations);
  id.declared_fit = fit_channel(declared_fit, signals, split, options.fit);
  progress.report(1);
  search_from(id, id.declared_fit, signals, split, options, progress, 1);
  if (proposes_kind(options, signals.channel)) {
    // The declared kind is wrong when its parameters end at a physical bound, either at once or
    // once the search has explained the rest of the force.
    auto hits = id.declared_fit.bound_hits;
    hits.insert(hits.end(), id.final_fit.bound_hits.begin(), id.final_fit.bound_hits.end());
    if (!hits.empty()) {
      // compare_kinds reports the kinds fitted so far; they follow the first search's units.
      SelectionOptions counted = options;
      counted.progress = [&](std::size_t kinds) { progress.report(1 + search_units + kinds); };
      id.kind = compare_kinds(signals, split, hits, counted, declarations);
      const std::size_t kinds_done = specimen_kinds().size();
      progress.report(1 + search_units + kinds_done);
      if (id.kind->proposed) {
        id.declared_search_final = id.final_fit;
        id.declared_search_final->prediction.clear();
        search_from(id, id.kind->ranking.front().fit, signals, split, options, progress,
                    1 + search_units + kinds_done);
      }
    }
    progress.report(selection_units(options, signals.channel));
  }
  attribute_shares(id, signals, split, options.fit);
  id.noise_floor = noise_floor(signals.input, signals.target, signals.dt);
  id.search_heldout_error = id.final_fit.heldout_error;
  id.final_evidence = residual_evidence(signals, id.final_fit.prediction);
  return id;
}

}  // namespace rths::identify
