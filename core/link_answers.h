#pragma once
// The network between the integrator and a lab, in process: which answer the integrator uses at
// each step when its commands and the lab's answers cross a link with lag, jitter, loss and drift.
// The actuator's command is never touched: the lab evaluates every command it receives in turn,
// and the link decides only when (and whether) each answer reaches the integrator.
//
// One way (LinkWay, config LinkLag; the same equations as runtime::LagInjector, so a case means
// the same in process as `rths sites` injects on a node), for the message of step k arriving at
// time t (ns):
//   lost      with probability `loss` (a uniform draw, first, when loss > 0)
//   delay   = max(0, one_way_delay + jitter N(0,1))   (a normal draw when jitter > 0)
//   extra   = drift_rate k dt + (spike_delay when k % spike_every < spike_steps)   (s)
//   dropped when drop_first_step <= k < drop_first_step + drop_steps
//   release = max(t + delay + extra, previous release)  -- FIFO: a way does not reorder
// std::mt19937_64 seeded with `seed`, one sequence per way.
//
// A link (LinkModel): command k leaves at t_k = k dt, reaches the lab through to_node, and its
// answer leaves the lab as it arrives and comes back through from_node: arrival a_k, or never.
// Answer schedule: used[k] = the newest j <= k with a_j <= t_k (0: none yet, the lab at rest).
// A link of d each way without jitter or loss uses the answer of step k - round(2 d / dt): the
// same as a time shift of 2d on the command, the specimen being time-invariant.
// Deterministic for given seeds; allocation only for the returned schedule.

#include <cstdint>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "core/answer_replay.h"

namespace rths::core {

struct LinkWay {
  double one_way_delay = 0.0;  // s
  double jitter = 0.0;         // s, standard deviation
  std::uint64_t seed = 0;
  double loss = 0.0;                                 // probability in [0, 1)
  double drift_rate = 0.0;                           // s of extra delay per s of simulated time
  double spike_delay = 0.0;                          // s
  std::int64_t spike_every = 0, spike_steps = 0;     // steps
  std::int64_t drop_first_step = 0, drop_steps = 0;  // steps
};

struct LinkModel {
  LinkWay to_node;    // the command's way to the lab
  LinkWay from_node;  // the answer's way back
};

// One way's FIFO lag (equations above).
class LinkWayLag {
 public:
  LinkWayLag(const LinkWay& way, double dt);
  // Release time (ns) of the message of `step` arriving at `arrival_ns`; nullopt: lost. A
  // message of no step (step < 0) is never dropped by step and carries no drift or spike.
  std::optional<std::int64_t> release(std::int64_t arrival_ns, std::int64_t step);
  // s, of the last released message: its lag without the drift and spikes (what a node reports).
  double last_delay() const { return last_delay_; }
  // Whether any term is on.
  bool active() const;

 private:
  LinkWay way_;
  double dt_;
  std::mt19937_64 rng_;
  std::normal_distribution<double> normal_{0.0, 1.0};
  std::uniform_real_distribution<double> uniform_{0.0, 1.0};
  std::int64_t last_release_ = 0;
  double last_delay_ = 0.0;
};

// used[k] for k in [0, steps) (schedule above); dt: s, > 0.
std::vector<std::int64_t> link_answer_steps(const LinkModel& link, double dt, std::size_t steps);

// The lag a link adds at least (s): both ways' one_way_delay, the round trip before jitter and
// drift; what the loop's critical-delay check weighs.
double nominal_round_trip(const LinkModel& link);
// One line: "link 30 ms + 30 ms, jitter 2.5 ms, loss 1 %, drift 0.1 ms/s" (per way when they
// differ: "link to 30 ms jitter 2.5 ms / from 20 ms").
std::string describe_link(const LinkModel& link);

// The schedule of a run of `steps` whose actuator a answers over links[a] (answer_replay.h).
AnswerSchedule link_schedule(const std::vector<LinkModel>& links, double dt, std::size_t steps);

// What a schedule did, from the first step that used an answer: the answers used (each counted
// once), steps that used the same answer as the step before (one late or lost: the integrator
// kept the last force), answers never used (lost, or overtaken within one step), and the
// answers' age k - used[k], in steps.
struct LinkAnswerStats {
  std::size_t used_answers = 0, repeated_steps = 0, unused_answers = 0;
  std::int64_t median_age = 0, max_age = 0;  // steps
};
LinkAnswerStats link_answer_stats(const std::vector<std::int64_t>& used);

}  // namespace rths::core
