#pragma once
// AnswerReplay: the answers a distributed loop used, replayed in an in-process run.
//
// In real time the coordinator does not wait for every answer: at step k it uses each node's
// newest answer, which may answer an older command j < k (a late answer, an overrun that left the
// node behind). The node still evaluated every command in turn, so in process the replay is:
// evaluate step k as usual, keep its outputs, and hand the integrator those of step j.
//
// Schedule (AnswerSchedule): per source, the step whose answer the loop used at each step k
// (0 = no answer yet: the outputs at rest, all zero; empty = always step k). Sources: each
// actuator (its realised drift, m, and measured force, N) and each storey's numerical part (its
// shear, N), as a node hosting it answered.
// step(k, shear, realised, force): input the fresh outputs of step k (k >= 1, one call per step,
//   k increasing by one); output, in place, the outputs of the step each source used at k.
//   A step the schedule names that is not in [0, k] is the schedule's fault: std::invalid_argument
//   naming the source and step (a record's answer cannot answer a command not yet sent).
// State: every source's outputs of every step so far (the whole run: sized at construction for
// `steps`, no allocation in step()).

#include <cstdint>
#include <vector>

#include "core/structure.h"

namespace rths::core {

struct AnswerSchedule {
  std::vector<std::vector<std::int64_t>> actuator_used;  // [actuator][k]; an empty row: fresh
  std::vector<std::vector<std::int64_t>> storey_used;    // [storey][k]; an empty row: fresh
  // Steps at which any source used an older answer than the step's own.
  std::size_t late_steps() const;
};

class AnswerReplay {
 public:
  // @pre schedule rows are empty or hold at least `steps` entries.
  AnswerReplay(AnswerSchedule schedule, int storeys, int actuators, std::size_t steps);
  void step(std::size_t k, Vec& shear, Vec& realised, Vec& force);

 private:
  static double used_value(const std::vector<std::int64_t>& used,
                           const std::vector<double>& history, std::size_t k, const char* kind,
                           std::size_t index);
  AnswerSchedule schedule_;
  // [source][step]: storeys' shears, actuators' realised drifts and forces.
  std::vector<std::vector<double>> shear_, realised_, force_;
};

}  // namespace rths::core
