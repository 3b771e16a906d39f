#pragma once
// What a front end asks of identify, as its user wrote it (names, not enums), turned into
// IdentifyOptions by one rule for the CLI (`rths identify`) and Python (`rths.identify`) alike.
//
// Input: IdentifyRequest (channel and effect names, "none" or an empty name for no effect, the
// held-out share and mode, the selection's limits and the search's cost). `argument` maps a field
// name ("declared_actuator") to how the front end spells it ("--declared-actuator", or
// "declared_actuator" in Python) for messages. Output: IdentifyOptions. Throws
// std::invalid_argument naming the argument for an unknown channel or effect, an effect that does
// not apply to its channel, no channel, a held-out share outside (0, 1) or max_steps outside [0,
// 1000].

#include <cstddef>
#include <functional>
#include <string>
#include <vector>

#include "identify/fit/identify.h"

namespace rths::identify {

struct IdentifyRequest {
  std::vector<std::string> channels{"measured", "force"};
  std::vector<std::string> declared_actuator{"delay"}, declared_specimen{"stiffness"};
  std::vector<std::string> candidates;  // empty: the whole library for each channel
  double holdout = 0.3;                 // share of the record held out
  std::string holdout_mode = "blocks";  // blocks | last
  std::size_t holdout_blocks = 10;
  std::size_t max_steps = 6;      // effects added per channel, at most
  double min_improvement = 0.05;  // held-out error must fall by this share
  double penalty = 0.01;          // relative penalty per added parameter
  std::size_t search_decimation = 0, search_samples = 12000;
  double search_tolerance = 1e-6;
  int search_iterations = 30;
};

using ArgumentName = std::function<std::string(const std::string& field)>;

IdentifyOptions identify_options(const IdentifyRequest& request, const ArgumentName& argument);

}  // namespace rths::identify
