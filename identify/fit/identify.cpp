#include "identify/fit/identify.h"

#include <algorithm>
#include <cmath>

namespace rths::identify {

const ChannelIdentification* Identification::find(Channel channel) const {
  for (const auto& c : channels) {
    if (c.channel == channel) return &c;
  }
  return nullptr;
}

std::vector<const SelectionStep*> Identification::steps() const {
  std::vector<const SelectionStep*> out;
  for (Channel ch : {Channel::kMeasured, Channel::kForce}) {
    if (const auto* c = find(ch)) {
      for (const auto& s : c->steps) out.push_back(&s);
    }
  }
  return out;
}

std::size_t identify_units(const IdentifyOptions& options) {
  std::size_t total = 0;
  for (Channel channel : options.channels) total += selection_units(options.selection, channel) + 1;
  return total;
}

namespace {

// Refits the search's models at the full rate, from the search's parameters (the declared one
// also from its declared values: full_rate_declared); the ranking keeps
// the search's errors. A step that paid on the search data but not at the full rate is dropped,
// with every step after it.
// The declared model at the full rate, refitted from the search's parameters and from its
// declared values (fit_declared at the full rate): a decimated search can carry a non-smooth
// model (a velocity limit, backlash) into another minimum. The lower held-out error stands.
FitResult full_rate_declared(const ChannelIdentification& id, const ChannelSignals& signals,
                             const Split& split, const FitOptions& full_fit,
                             const std::vector<ParamDeclaration>& declarations) {
  FitResult from_search = fit_channel(id.declared_fit.model, signals, split, full_fit);
  if (declarations.empty()) return from_search;
  FitResult from_declared = fit_channel(
      fit_declared(signals, split, id.declared, full_fit, declarations), signals, split, full_fit);
  return from_declared.heldout_error < from_search.heldout_error ? from_declared : from_search;
}

void refit_at_full_rate(ChannelIdentification& id, const ChannelSignals& signals,
                        const Split& split, const FitOptions& full_fit,
                        const std::vector<ParamDeclaration>& declarations) {
  id.declared_fit = full_rate_declared(id, signals, split, full_fit, declarations);
  id.start_fit = id.kind && id.kind->proposed
                     ? fit_channel(id.start_fit.model, signals, split, full_fit)
                     : id.declared_fit;
  if (id.kind) {
    for (auto& trial : id.kind->ranking) trial.fit.prediction.clear();
  }
  FitResult previous = id.start_fit;
  for (std::size_t k = 0; k < id.steps.size(); ++k) {
    auto& step = id.steps[k];
    step.before = previous;
    step.evidence_before = residual_evidence(signals, previous.prediction);
    step.after = fit_channel(step.after.model, signals, split, full_fit);
    for (auto& trial : step.ranking) trial.fit.prediction.clear();
    if (!(step.after.heldout_error < step.before.heldout_error)) {
      // Paid on the search data but not at the full rate: not added, and nothing after it.
      id.dropped_at_full_rate.assign(id.steps.begin() + static_cast<std::ptrdiff_t>(k),
                                     id.steps.end());
      id.steps.resize(k);
      break;
    }
    previous = step.after;
  }
  id.final_fit = previous;
  attribute_shares(id, signals, split, full_fit);
  id.final_evidence = residual_evidence(signals, previous.prediction);
  for (auto& trial : id.last_ranking) trial.fit.prediction.clear();
}

}  // namespace

Identification identify(const MeasuredData& data, const IdentifyOptions& options) {
  Identification result;
  result.source = data.source;
  result.samples = data.size();
  result.dt = data.dt;
  std::size_t factor = options.search_decimation;
  if (factor == 0) {
    factor = std::max<std::size_t>(1, (data.size() + options.search_samples - 1) /
                                          std::max<std::size_t>(1, options.search_samples));
  }
  result.search_decimation = factor;
  const MeasuredData search = decimated(data, factor);
  const Split search_split = holdout_split(search.size(), options.holdout_fraction,
                                           options.holdout_mode, options.holdout_blocks);
  result.split = holdout_split(data.size(), options.holdout_fraction, options.holdout_mode,
                               options.holdout_blocks);
  const std::size_t total = identify_units(options);
  std::size_t channel_start = 0, last_done = 0;
  std::string last_stage;
  const auto report = [&](std::size_t done, const std::string& stage) {
    last_done = std::min(done, total);
    last_stage = stage;
    if (options.progress) options.progress({last_done, total, stage});
  };
  // Every solver iteration repeats the last report: progress moves while one fit runs long.
  const auto heartbeat = [&] { report(last_done, last_stage); };
  FitOptions full_fit = options.selection.fit;
  full_fit.on_iteration = heartbeat;

  for (Channel channel : options.channels) {
    const auto& declared =
        channel == Channel::kMeasured ? options.declared_actuator : options.declared_specimen;
    const ChannelSignals search_signals = make_signals(search, channel);
    const auto& declarations =
        channel == Channel::kMeasured ? options.actuator_parameters : options.specimen_parameters;
    SelectionOptions selection = options.selection;
    const std::string name = channel_name(channel);
    selection.progress = [&](std::size_t units) { report(channel_start + units, last_stage); };
    selection.stage = [&](const std::string& what) { report(last_done, name + ": " + what); };
    selection.fit.on_iteration = heartbeat;
    if (factor > 1) {
      selection.fit.tolerance = options.search_tolerance;
      selection.fit.max_iterations =
          std::min(selection.fit.max_iterations, options.search_iterations);
    }
    const std::size_t search_units = selection_units(options.selection, channel);
    report(channel_start, name + ": search");
    ChannelIdentification id =
        identify_channel(search_signals, search_split, declared, selection, declarations);
    report(channel_start + search_units, name + ": full-rate refit");
    ChannelSignals signals = make_signals(data, channel);
    if (factor > 1) refit_at_full_rate(id, signals, result.split, full_fit, declarations);
    id.noise_floor = noise_floor(signals.input, signals.target, signals.dt);
    result.channels.push_back(std::move(id));
    result.signals.push_back(std::move(signals));
    channel_start += search_units + 1;
    report(channel_start, name + ": done");
  }
  return result;
}

ForceColumn force_column(const std::vector<Channel>& channels) {
  const bool force = std::find(channels.begin(), channels.end(), Channel::kForce) != channels.end();
  return force ? ForceColumn::kRequired : ForceColumn::kOptional;
}

}  // namespace rths::identify
