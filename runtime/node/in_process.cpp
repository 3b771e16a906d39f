#include "runtime/node/in_process.h"

#include "runtime/node/plan.h"

namespace rths::runtime {

core::HybridSetup in_process_setup(const study::PreparedStudy& prepared,
                                   const config::Case& study_case) {
  const core::HybridSetup setup = study::setup_for_case(prepared, study_case);
  return with_node_compensation(setup, plan_deployment(setup, prepared.config.deployment()));
}

}  // namespace rths::runtime
