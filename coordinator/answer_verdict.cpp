#include "coordinator/answer_verdict.h"

#include <sstream>

namespace rths::coordinator {

std::optional<std::string> answer_shortfall(int node_id, std::uint64_t fresh, std::uint64_t steps,
                                            double min_fraction) {
  if (steps == 0 || static_cast<double>(fresh) >= min_fraction * static_cast<double>(steps))
    return std::nullopt;
  std::ostringstream out;
  out << "failed: node " << node_id << " answered " << fresh << " of " << steps
      << " steps (at least " << 100.0 * min_fraction << " % needed)";
  return out.str();
}

}  // namespace rths::coordinator
