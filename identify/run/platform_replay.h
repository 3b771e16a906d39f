#pragma once
// The platform's part of a run as its record tells it, for the re-run to replay
// (core/answer_replay.h): at each step k, the step whose answer the coordinator's loop used from
// each node (StepRecord.links[].answered_step), spread to what that node answers for: its
// actuators (emulators, controllers) or its numerical storeys (substructure nodes), as the
// coordinator's plan assigns them (runtime/node/answer_sources.h). In lockstep every step waits for its own answers; in real time
// a late answer or an overrun leaves a step on an older one, which is the platform's doing, not
// the rig's.
//
// Input: the record's steps (the first `steps` of them), which node answers for which sources
// (runtime::answer_sources of the record's study).
// Output (PlatformReplay): the schedule (a row left empty for a source always on its own
// answer); the steps on an older answer (any source) with the mean and largest age of the
// answers they used (steps: k - answered step).
// aligned(used, recorded): a series the loop recorded at each step (the answer it used: a
// realised drift, a measured force) put back at the step each answer answers: y[j] = recorded[k]
// for the first k that used step j's answer; a step whose answer the loop never used is
// interpolated linearly between its neighbours (held before the first and after the last). The
// rig is identified on these series, so a platform's lateness is not taken for the rig's lag.
// An empty `used`: the series as recorded.

#include <cstdint>
#include <string>
#include <vector>

#include "core/answer_replay.h"
#include "rths/proto/runtime.pb.h"
#include "runtime/node/answer_sources.h"

namespace rths::identify {

struct PlatformReplay {
  core::AnswerSchedule schedule;
  std::size_t steps = 0, late_steps = 0;
  double mean_age = 0.0;  // steps, over the answers used late
  std::int64_t oldest = 0;
  std::string text() const;  // "412 of 15,000 steps (2.75 %) on an older answer: mean age ..."
};

// `storeys`, `actuators`: the run's (the schedule's rows).
PlatformReplay platform_replay(const std::vector<const runtime::StepRecord*>& steps,
                               std::size_t count, const std::vector<runtime::NodeSources>& nodes,
                               int storeys, int actuators);

// Actuator a's row of `schedule` (0-based); empty when it has none.
std::vector<std::int64_t> actuator_row(const core::AnswerSchedule& schedule, int a);

std::vector<double> aligned(const std::vector<std::int64_t>& used,
                            const std::vector<double>& recorded);

}  // namespace rths::identify
