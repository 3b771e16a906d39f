#pragma once
// Substructure node: hosts numerical storeys of the study (core::NumericalSubstructure with only
// its storeys' models). Input: Command.drift, one per hosted storey (m). Output: Feedback.force,
// the storey shears (N), same order. Each command is a trial immediately committed: the
// coordinator's explicit integrators evaluate each step exactly once.

#include <memory>

#include "core/substructure.h"
#include "runtime/node/node_service.h"

namespace rths::substructure_nodes {

class SubstructureService final : public runtime::NodeService {
 public:
  SubstructureService(std::int32_t node_id, std::string expected_run_id);

 protected:
  int configure(const runtime::Assign& assign) override;
  void compute(const runtime::Command& command, runtime::Feedback& feedback) override;

 private:
  std::unique_ptr<core::NumericalSubstructure> numerical_;
  std::vector<int> storeys_;
  core::Vec drift_, shear_;
};

}  // namespace rths::substructure_nodes
