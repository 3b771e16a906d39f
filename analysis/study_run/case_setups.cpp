#include "analysis/study_run/case_setups.h"

#include <stdexcept>
#include <string>
#include <utility>

#include "study/case_link.h"

namespace rths::analysis {

CaseLoop case_loop(const core::HybridSetup& setup, double extra_lag) {
  return {core::setup_loop_parts(setup,
                                 std::vector<double>(setup.partition.actuator_storeys.size(), 0.0)),
          study::answer_lag(setup) + extra_lag};
}

namespace {

// The lending below holds only while a case's setup keeps the study's model: checked by its
// size and sparsity (cheap at any size), so that a case that changed it is refused, not run on
// another case's model.
void require_same_model(const core::StructuralModel& base, const core::HybridSetup& setup,
                        const std::string& case_name) {
  const core::StructuralModel& m = setup.model;
  const bool same = m.dofs() == base.dofs() && m.is_sparse() == base.is_sparse() &&
                    m.sparse_stiffness.nonZeros() == base.sparse_stiffness.nonZeros() &&
                    m.sparse_damping.nonZeros() == base.sparse_damping.nonZeros();
  if (!same)
    throw std::logic_error("case '" + case_name +
                           "' changes the study's structural model: its setups cannot share one");
}

}  // namespace

CaseSetups::CaseSetups(const study::PreparedStudy& prepared,
                       const std::vector<const config::Case*>& cases, double extra_lag) {
  if (cases.empty()) throw std::invalid_argument("CaseSetups: no cases");
  setups_.reserve(cases.size());
  for (const config::Case* study_case : cases) {
    // The model of the case before is released before this one's copy is made.
    if (!setups_.empty()) setups_.back().model = core::StructuralModel{};
    setups_.push_back(study::setup_for_case(prepared, *study_case));
    require_same_model(prepared.base.model, setups_.back(), study_case->name());
    loops_.push_back(case_loop(setups_.back(), extra_lag));
  }
  lent_ = setups_.size() - 1;
}

const core::HybridSetup& CaseSetups::lend(std::size_t i) {
  core::HybridSetup& to = setups_.at(i);
  if (i != lent_) {
    to.model = std::exchange(setups_[lent_].model, core::StructuralModel{});
    lent_ = i;
  }
  return to;
}

}  // namespace rths::analysis
