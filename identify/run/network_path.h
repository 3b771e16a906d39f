#pragma once
// The network path of one link of a distributed run, identified from the answers its record holds
// (runtime/record/measurements.h LinkSeries: one entry per answer, at the simulated time of the
// step that carried it).
//
// Input: per answer i, the round trip r_i (s, coordinator clock: feedback received - command
// sent), the lag the node injected q_i (s) and the step it answers; the step dt (s); and what the
// run's config declared for the link (DeclaredLink: the node's receive_lag + send_lag).
// Excess x_i = r_i - q_i (s): what the network and the processes added beyond the injection.
//   bias        median(x)
//   jitter      1.4826 MAD(x) (a standard deviation robust to spikes)
//   spikes      answers with x_i > bias + max(6 jitter, kMinSpike): count, and their period when
//               they recur: bursts (each spike within 3 steps of the one before) whose starts'
//               pairwise spacings pile up at one spacing P (>= 3 pairs, 4 standard deviations above
//               the spacings' mean density; P's whole fractions down to P/5 preferred when they
//               hold half as many pairs), with at least 3 starts, and half the slots of the run, on
//               the grid t0 + k P (within 3 steps or 2 % of P): a busy host's stray spikes spread
//               evenly and hide neither P nor t0. Looked for at the threshold and at the
//               spikes' height quantiles 50, 75 and 90 % (on a loaded host the strays outnumber
//               periodic spikes that stand above most of them), the level whose grid covers the
//               most of its slots kept; the candidate is judged on the held-out answers without
//               the spikes off its slots (strays neither model explains)
//   drift       x modelled as bias + a s + D(s; c) (a linear trend and model.h's slow cosine
//               series, kDriftTerms terms, whose zero-mean cosines alone round a ramp's ends off;
//               least squares over the answers that are not spikes); its range over the run (s)
//   lost        steps no answer ever came for: a gap of g steps in answered_step between two
//               answers taken in a row, over which the coordinator's answer count (LinkSample
//               answers) rose by r + 1, holds r answers superseded within a step (received, then
//               replaced by a newer one before the loop took it) and g - r lost ones; the longest
//               burst of consecutive lost ones (per gap g - r: a superseded answer came a step or
//               so late, at the gap's edge, so the lost ones lie together). A record without the
//               count: every gap is lost.
//   late        answers carried by a later step than the one after the step they answer
//   injected    q against the declared round trip: a node that injected what the config did not
//               declare (mean difference, s)
// The declared model of x is the constant bias. Each candidate is judged on held-out answers
// (data.h holdout_split, blocks, 30 %): the RMS of x about the model over the held-out answers,
// declared vs with the candidate fitted on the training answers only:
//   drifting delay   bias + a s + D(s; c)              pays when the held-out RMS falls by >= 20 %
//   periodic spikes  bias + A at times t0 + k P        and the fall is above kMinEffect (s)
//                    (P, t0, A from the training spikes)
// and, judged by counting, not by a fit:
//   lost answers     a burst of at least 3 consecutive lost answers, or lost answers on a link
//                    declared lossless (an iid loss of probability l makes a burst of L in N
//                    answers with probability ~ N l^L; bursts beyond 1e-3 of it are named)
//   injection        |mean(q) - declared| > max(0.1 ms, 5 %): the node injected other than declared
// An effect the config declares (its links' network emulation: drift, spikes, dropped commands) is
// fitted as the others but not named.
// Shares: each fitted effect's held-out RMS removed over the sum of them.

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "identify/run/clock_offset.h"

namespace rths::identify {

inline constexpr double kMinSpike = 1.0e-3;   // s
inline constexpr double kMinEffect = 2.0e-4;  // s of held-out RMS an effect must remove

struct DeclaredLink {
  double round_trip = 0.0;  // s, mean lag injected each way, summed
  double jitter = 0.0;      // s, standard deviation of the injected round trip
  double loss = 0.0;        // probability that one exchange loses its command or its answer
  // The link's declared network emulation (config NetworkEmulation): a drift, spikes, a burst of
  // dropped commands.
  bool drift = false, spikes = false, drops = false;
};

struct LinkAnswers {
  int node_id = 0;
  std::vector<double> time;  // s
  std::vector<std::int64_t> answered_step;
  // The coordinator's count of answers accepted by each one (runtime LinkSeries answers); empty
  // or 0 when the record has none.
  std::vector<std::int64_t> answers;
  std::vector<double> round_trip, injected;  // s
};

struct NetworkEffect {
  std::string name;    // "drifting delay", "periodic spikes", "lost answers", "injection",
                       // "clock offset"
  std::string detail;  // what was measured, with units
  double heldout_before = 0.0, heldout_after = 0.0;  // s, RMS of x about the model (fitted ones)
  double share = 0.0;  // of the held-out RMS the fitted effects removed
};

struct NetworkPath {
  int node_id = 0;
  std::size_t answers = 0, lost = 0, longest_burst = 0, late = 0, spikes = 0;
  std::size_t superseded = 0;  // answers received, then replaced within a step by a newer one
  double bias = 0.0, jitter = 0.0, drift_range = 0.0, spike_period = 0.0;  // s
  double spike_height = 0.0;   // s, median excess of the spikes above the bias
  double injected_mean = 0.0;  // s
  // The two hosts' clock offset from the answers' one-way stamps (clock_offset.h); absent when
  // the record has too few. Named among `effects` as "clock offset" when it matters.
  std::optional<ClockOffset> clock;
  DeclaredLink declared;
  double heldout_declared = 0.0;       // s, RMS of x about the bias over the held-out answers
  std::vector<NetworkEffect> effects;  // the undeclared effects named, fitted ones first
  // Per answer: its time, round trip, injected lag and the identified model of the round trip
  // (injected + the excess's median over the training answers, + the drift and the periodic
  // spikes when they were named), s.
  std::vector<double> time, round_trip, injected, model;
};

// @pre answers has at least 20 answers (fewer: no statistics, throws std::invalid_argument
// naming the node). dt > 0 (s).
NetworkPath identify_network_path(const LinkAnswers& answers, const DeclaredLink& declared,
                                  double dt);

}  // namespace rths::identify
