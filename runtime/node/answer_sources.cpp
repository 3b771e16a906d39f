#include "runtime/node/answer_sources.h"

#include "runtime/node/plan.h"

namespace rths::runtime {

std::vector<NodeSources> answer_sources(const config::Study& study, double dt,
                                        const std::filesystem::path& base_dir) {
  const core::HybridSetup base = study::base_setup(study, dt, base_dir);
  const DeploymentPlan plan = plan_deployment(base, study.deployment());
  std::vector<NodeSources> out;
  for (const NodePlan& node : plan.nodes) {
    const bool numerical = node.spec.kind() == config::NodeSpec::SUBSTRUCTURE;
    out.push_back({node.spec.id(), numerical, numerical ? node.storeys : node.actuators});
  }
  return out;
}

}  // namespace rths::runtime
