#pragma once
// From a run record to measurements: the one reader every consumer of a record uses (rths launch,
// rths sites, joint-lag, the coordinator's own summary), so they cannot disagree.
//
//   per-step columns   a core::SimulationResult: time, displacement, velocity, acceleration (per
//                      recorded DOF: every DOF, or the header's recorded_dofs, which become the
//                      result's `dofs`), command, realised, measured force (per actuator); SI.
//   per link           one series per node, one entry per ANSWER, not per step. The rule for
//                      repeated answers: an answer counts once, at the first step that carries it.
//                      In real time a step with no newer answer reuses the previous one; those
//                      repeats are not new measurements. Step 0 and "no answer yet" (answered
//                      step 0) carry none.
//   LagSummary         of each series' round trip and injected lag (s).
// LinkLagAccumulator applies the same rule step by step, for a live run.

#include <map>
#include <string>
#include <vector>

#include "core/simulation.h"
#include "runtime/node/lag.h"
#include "runtime/record/record.h"

namespace rths::runtime {

struct LinkSeries {
  int node_id = 0;
  std::vector<double> time;  // s, simulated time of the step that carried it
  std::vector<std::int64_t> answered_step;
  // Answers the coordinator had accepted from the node by this one, superseded ones included
  // (LinkSample.answers; 0 in a record without the count).
  std::vector<std::int64_t> answers;
  std::vector<double> round_trip, injected;      // s
  std::vector<double> one_way_down, one_way_up;  // s (include clock offset across hosts)
  LagSummary round_trip_summary() const { return summarize(round_trip); }
  LagSummary injected_summary() const { return summarize(injected); }
};

class LinkLagAccumulator {
 public:
  // Reserves room for `answers` answers per link and touches it (so a live run neither allocates
  // nor faults in a page per step).
  void reserve(int node_id, std::size_t answers);
  // One step's sample of one link; ignored when it carries no new answer.
  void add(double time, const LinkSample& sample);
  const std::map<int, LinkSeries>& links() const { return links_; }

 private:
  std::map<int, LinkSeries> links_;
};

struct RunMeasurements {
  std::string clock;      // "lockstep" or "real_time" (header)
  std::string case_name;  // header
  core::SimulationResult steps;
  std::map<int, LinkSeries> links;  // by node id
  bool has_footer = false;          // false: the run was cut short
  RunFooter footer;
};

// Throws std::invalid_argument when the record has no header.
RunMeasurements measure_run(const RecordContents& record);

}  // namespace rths::runtime
