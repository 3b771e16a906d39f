#include "view/record_limits.h"

#include <algorithm>

#include "runtime/record/record_checks.h"

namespace rths::view {

std::optional<std::string> refused_header(const runtime::RunHeader& header) {
  const std::string bound = " outside [0, " + std::to_string(runtime::kMaxRecordDofs) + "]";
  if (header.dofs() < 0 || header.dofs() > runtime::kMaxRecordDofs)
    return "run header: dofs " + std::to_string(header.dofs()) + bound;
  if (header.actuators() < 0 || header.actuators() > runtime::kMaxRecordDofs)
    return "run header: actuators " + std::to_string(header.actuators()) + bound;
  if (header.link_node_ids_size() > runtime::kMaxRecordDofs)
    return "run header: link_node_ids holds " + std::to_string(header.link_node_ids_size()) +
           " links," + bound;
  for (int i = 0; i < header.recorded_dofs_size(); ++i) {
    const int dof = header.recorded_dofs(i);
    if (dof < 0 || dof >= header.dofs() || (i > 0 && dof <= header.recorded_dofs(i - 1)))
      return "run header: recorded_dofs[" + std::to_string(i) + "] " + std::to_string(dof) +
             " is not a DOF of 0.." + std::to_string(header.dofs() - 1) +
             " above the one before it";
  }
  return std::nullopt;
}

int prediction_column(const std::vector<int>& kept, int columns, int dof) {
  if (kept.empty()) return dof >= 0 && dof < columns ? dof : -1;
  const auto at = std::lower_bound(kept.begin(), kept.end(), dof);
  return at != kept.end() && *at == dof ? static_cast<int>(at - kept.begin()) : -1;
}

}  // namespace rths::view
