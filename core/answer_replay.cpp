#include "core/answer_replay.h"

#include <algorithm>
#include <stdexcept>
#include <string>

namespace rths::core {

std::size_t AnswerSchedule::late_steps() const {
  std::size_t steps = 0;
  for (const auto* rows : {&actuator_used, &storey_used})
    for (const auto& row : *rows) steps = std::max(steps, row.size());
  std::size_t late = 0;
  for (std::size_t k = 1; k < steps; ++k) {
    bool older = false;
    for (const auto* rows : {&actuator_used, &storey_used})
      for (const auto& row : *rows)
        older = older || (k < row.size() && row[k] != static_cast<std::int64_t>(k));
    late += older ? 1 : 0;
  }
  return late;
}

AnswerReplay::AnswerReplay(AnswerSchedule schedule, int storeys, int actuators, std::size_t steps)
    : schedule_(std::move(schedule)),
      shear_(static_cast<std::size_t>(storeys), std::vector<double>(steps, 0.0)),
      realised_(static_cast<std::size_t>(actuators), std::vector<double>(steps, 0.0)),
      force_(static_cast<std::size_t>(actuators), std::vector<double>(steps, 0.0)) {
  schedule_.actuator_used.resize(realised_.size());
  schedule_.storey_used.resize(shear_.size());
  for (const auto* rows : {&schedule_.actuator_used, &schedule_.storey_used})
    for (const auto& row : *rows)
      if (!row.empty() && row.size() < steps)
        throw std::invalid_argument("answer schedule: " + std::to_string(row.size()) +
                                    " steps for a run of " + std::to_string(steps));
}

double AnswerReplay::used_value(const std::vector<std::int64_t>& used,
                                const std::vector<double>& history, std::size_t k, const char* kind,
                                std::size_t index) {
  if (used.empty()) return history[k];
  const std::int64_t j = used[k];
  if (j < 0 || j > static_cast<std::int64_t>(k))
    throw std::invalid_argument("answer schedule: " + std::string(kind) + " " +
                                std::to_string(index + 1) + " at step " + std::to_string(k) +
                                " uses the answer to step " + std::to_string(j));
  return history[static_cast<std::size_t>(j)];
}

void AnswerReplay::step(std::size_t k, Vec& shear, Vec& realised, Vec& force) {
  for (std::size_t s = 0; s < shear_.size(); ++s) {
    const auto i = static_cast<Eigen::Index>(s);
    shear_[s].at(k) = shear[i];
    if (!schedule_.storey_used[s].empty())
      shear[i] = used_value(schedule_.storey_used[s], shear_[s], k, "storey", s);
  }
  for (std::size_t a = 0; a < realised_.size(); ++a) {
    const auto i = static_cast<Eigen::Index>(a);
    realised_[a].at(k) = realised[i];
    force_[a][k] = force[i];
    const auto& used = schedule_.actuator_used[a];
    if (used.empty()) continue;
    realised[i] = used_value(used, realised_[a], k, "actuator", a);
    force[i] = used_value(used, force_[a], k, "actuator", a);
  }
}

}  // namespace rths::core
