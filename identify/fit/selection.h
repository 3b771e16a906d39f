#pragma once
// Greedy forward selection of missing effects, judged on held-out data.
//
// 1. Fit the declared model (effects added one by one from their guesses, then all refitted).
// 2. For every candidate effect not yet in the model: add it, refit ALL parameters jointly from
//    each of its starting guesses (best training cost wins), and measure the held-out error e_h.
// 3. Score = e_h (1 + penalty_per_parameter * parameters added). The best-scoring candidate is
//    added only if it pays: e_h <= (1 - min_relative_improvement) * e_h(current) and its score
//    beats the current model's. Otherwise stop. Repeat up to max_steps.
// Never adds an effect that does not pay: every step lowers the held-out error by the threshold.
// Wrong kind (force channel): when the declared fit, or the search's final model from it, ends at
// a physical bound the data push against (fit.h BoundHit, e.g. a negative stiffness), every
// specimen kind (specimen.h), each with a force offset/drift (a property of the load cell, not of
// the specimen), is fitted and ranked by the same score; the best kind with no bound hit is
// proposed and the search is run again from it. The declared fit is kept and reported.
// The candidate ranking and the residual evidence before each step are kept for the report.

#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "identify/fit/evidence.h"
#include "identify/fit/fit.h"
#include "identify/model/specimen.h"

namespace rths::identify {

struct SelectionOptions {
  std::vector<Effect> candidates;          // empty: the whole library for the channel
  double min_relative_improvement = 0.05;  // held-out error must fall by at least this share
  double penalty_per_parameter = 0.01;     // relative penalty per added parameter
  std::size_t max_steps = 6;
  bool propose_kind = true;  // force channel: propose a specimen kind when the declared is wrong
  FitOptions fit;
  // Progress of identify_channel, in units of work done so far for this channel (out of
  // selection_units): 1 for the declared fit; per search, max_steps rounds of P units each
  // (P = the candidates of the pool that apply to the channel; a round's trials fill its P units
  // in proportion), a search that stops early jumping to its end; on the force channel with
  // propose_kind, one unit per specimen kind compared and a second search, both skipped (jumped
  // over) when the declared kind stands. Never decreases; ends at selection_units.
  std::function<void(std::size_t units_done)> progress;
  // Called with what is fitted next ("declared model", "candidate first_order (round 2)",
  // "specimen kind bouc_wen"), so that progress can name it; empty = silent.
  std::function<void(const std::string& what)> stage;
};

// The units identify_channel reports through SelectionOptions::progress for `channel`.
std::size_t selection_units(const SelectionOptions& options, Channel channel);

struct KindTrial {
  SpecimenKind kind = SpecimenKind::kLinearSpring;
  double score = 0.0;  // held-out error (1 + penalty * parameters)
  FitResult fit;
  bool physical = true;  // no bound hit on a parameter of the kind's defining effects
};

struct KindProposal {
  std::vector<BoundHit> declared_hits;   // why the declared model is the wrong kind
  std::vector<KindTrial> ranking;        // physical kinds first, then by score
  std::optional<SpecimenKind> proposed;  // the best physical kind, if any fits
};

// Fits every specimen kind on the force channel and ranks them. @pre signals.channel is force.
// options.progress, when set, is called with the number of kinds fitted so far after each.
// Declarations (model.h) of parameters the kinds share with the declared model apply to them too.
KindProposal compare_kinds(const ChannelSignals& signals, const Split& split,
                           const std::vector<BoundHit>& declared_hits,
                           const SelectionOptions& options,
                           const std::vector<ParamDeclaration>& declarations = {});

struct CandidateTrial {
  Effect effect = Effect::kDelay;
  std::size_t added_params = 0;
  double train_error = 0.0, heldout_error = 0.0, score = 0.0;
  bool pays = false;
  FitResult fit;
};

struct SelectionStep {
  Channel channel = Channel::kMeasured;
  Effect effect = Effect::kDelay;
  FitResult before, after;
  Evidence evidence_before;             // of the residual the step explains
  std::vector<CandidateTrial> ranking;  // best score first
  // The effect's own part, independent of the order of the steps: the final model refitted
  // without it loses this much held-out error (own_error_removed = e_h(without) - e_h(final)),
  // and own_share is that part over the sum of every added effect's part.
  double own_error_removed = 0.0, own_share = 0.0;
};

struct ChannelIdentification {
  Channel channel = Channel::kMeasured;
  std::vector<Effect> declared;
  FitResult declared_fit;
  std::optional<KindProposal> kind;  // when the declared model was the wrong kind
  FitResult start_fit;               // the search's start: declared_fit or the proposed kind's
  std::optional<FitResult> declared_search_final;  // the search from the declared model, when
                                                   // it was replaced (prediction cleared)
  std::vector<SelectionStep> steps;
  FitResult final_fit;
  Evidence final_evidence;
  std::vector<CandidateTrial> last_ranking;  // the round in which nothing paid
  // Held-out error of the final model on the data the search ran on (rankings compare with it).
  double search_heldout_error = 0.0;
  // Estimated sensor noise of the target, normalised like the errors (evidence.h noise_floor):
  // no model can reach a held-out error below it.
  double noise_floor = 0.0;
  // Steps that paid on decimated search data but not when refitted at the full rate.
  std::vector<SelectionStep> dropped_at_full_rate;
};

// Fits `model` + `effect` from each starting guess of the effect (cartesian product of its
// parameters' guesses); returns the fit with the lowest training cost.
FitResult fit_with_effect(const ChannelModel& model, Effect effect, const ChannelSignals& signals,
                          const Split& split, const FitOptions& options);

// The declared effects fitted one by one (each from its guesses, or from its declared initial
// value), with `declarations` (model.h) carried by the model and every model grown from it; where
// the declarations give values, also every declared effect at them fitted jointly, and the lower
// training cost of the two stands.
ChannelModel fit_declared(const ChannelSignals& signals, const Split& split,
                          const std::vector<Effect>& declared, const FitOptions& options,
                          const std::vector<ParamDeclaration>& declarations = {});

ChannelIdentification identify_channel(const ChannelSignals& signals, const Split& split,
                                       const std::vector<Effect>& declared,
                                       const SelectionOptions& options,
                                       const std::vector<ParamDeclaration>& declarations = {});

// Fills own_error_removed and own_share of every step of `id` (drop-one refits of the final
// model on `signals` / `split`).
void attribute_shares(ChannelIdentification& id, const ChannelSignals& signals, const Split& split,
                      const FitOptions& options);

// The declared model by default: actuator = pure delay + gain, specimen = linear spring.
std::vector<Effect> default_declared(Channel channel);

}  // namespace rths::identify
