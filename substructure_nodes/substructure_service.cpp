#include "substructure_nodes/substructure_service.h"

#include <stdexcept>

#include "runtime/node/plan.h"

namespace rths::substructure_nodes {

SubstructureService::SubstructureService(std::int32_t node_id, std::string expected_run_id)
    : NodeService(node_id, config::NodeSpec::SUBSTRUCTURE, std::move(expected_run_id)) {}

int SubstructureService::configure(const runtime::Assign& assign) {
  const config::Case& study_case = study::find_case(assign.study(), assign.case_name());
  core::HybridSetup setup =
      runtime::setup_without_motion(assign.study(), assign.base_dir(), assign.dt(), study_case,
                                    [this](const std::string& what) { setup_phase(what); });
  const int n = static_cast<int>(setup.partition.numerical.size());
  std::vector<std::unique_ptr<core::RestoringForceModel>> models(n);
  storeys_.assign(assign.storeys().begin(), assign.storeys().end());
  for (int s : storeys_) {
    if (s < 0 || s >= n || !setup.partition.has_numerical(s))
      throw std::invalid_argument("storey " + std::to_string(s + 1) + " has no numerical part");
    if (setup.partition.numerical[s]) models[s] = setup.partition.numerical[s]->clone();
  }
  // A matrix part (a structure given by matrices): the plan has this node host every coupled DOF.
  setup_phase("building its numerical part (" + std::to_string(storeys_.size()) + " storeys)");
  numerical_ = std::make_unique<core::NumericalSubstructure>(std::move(models),
                                                             setup.partition.numerical_matrix);
  drift_ = core::Vec::Zero(n);
  shear_ = core::Vec::Zero(n);
  return static_cast<int>(storeys_.size());
}

void SubstructureService::compute(const runtime::Command& command, runtime::Feedback& feedback) {
  if (command.drift_size() != static_cast<int>(storeys_.size()))
    throw std::invalid_argument(label() + ": command has " + std::to_string(command.drift_size()) +
                                " drifts for " + std::to_string(storeys_.size()) + " storeys");
  for (std::size_t i = 0; i < storeys_.size(); ++i) drift_[storeys_[i]] = command.drift(i);
  numerical_->trial(drift_, shear_, nullptr);
  numerical_->commit();
  for (int s : storeys_) feedback.add_force(shear_[s]);
}

}  // namespace rths::substructure_nodes
