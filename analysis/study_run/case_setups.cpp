#include "analysis/study_run/case_setups.h"

#include <stdexcept>
#include <utility>

#include "study/case_link.h"

namespace rths::analysis {

CaseLoop case_loop(const core::HybridSetup& setup, double extra_lag) {
  return {core::setup_loop_parts(setup,
                                 std::vector<double>(setup.partition.actuator_storeys.size(), 0.0)),
          study::answer_lag(setup) + extra_lag};
}

CaseSetups::CaseSetups(const study::PreparedStudy& prepared,
                       const std::vector<const config::Case*>& cases, double extra_lag) {
  if (cases.empty()) throw std::invalid_argument("CaseSetups: no cases");
  setups_.reserve(cases.size());
  for (const config::Case* study_case : cases) {
    // The model of the case before is released before this one's copy is made.
    if (!setups_.empty()) setups_.back().model = core::StructuralModel{};
    setups_.push_back(study::setup_for_case(prepared, *study_case));
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
