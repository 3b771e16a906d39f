#pragma once
// Whether every node answered a real-time run, as its outcome says it: a run on which a node's
// answers never (or too seldom) arrived is never ok, whatever else it kept.
//   answer_shortfall   fresh < min_fraction x steps  ->  "failed: node N answered K of M steps
//                      (at least P % needed)"
// fresh: steps on which the node gave a fresh answer (one it had not given before); steps: the
// steps judged; min_fraction in [0, 1] (the coordinator uses kMinAnswerFraction).
// Nothing (nullopt) when the node answered enough, or when no step was judged.

#include <cstdint>
#include <optional>
#include <string>

namespace rths::coordinator {

// A real-time run needs a fresh answer from every node on at least 99 % of its steps.
inline constexpr double kMinAnswerFraction = 0.99;

std::optional<std::string> answer_shortfall(int node_id, std::uint64_t fresh, std::uint64_t steps,
                                            double min_fraction);

}  // namespace rths::coordinator
