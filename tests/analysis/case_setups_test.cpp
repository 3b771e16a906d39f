// A study's case setups built once (analysis/study_run/case_setups.h): each lent setup is the one
// study::setup_for_case builds, with the study's model; one model is alive at a time.
#include "analysis/study_run/case_setups.h"

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "study/case_link.h"
#include "study/study.h"

namespace rths::analysis {
namespace {

const std::filesystem::path kConfigs = RTHS_SOURCE_DIR "/configs";

// The 20-DOF frame given by matrices, 0.5 s of Imperial Valley, three cases of 0, 2 and 5 ms.
study::PreparedStudy frame20() {
  const std::string text =
      "name: \"frame20\" structure { matrices { mass { file: \"matrices/frame20_mass.mtx\" } "
      "stiffness { file: \"matrices/frame20_stiffness.mtx\" } } damping { modal_zeta: 0.05 } } "
      "motion { path: \"../data/ground_motions/RSN175_IMPVALL.H_H-E12140.AT2\" duration: 0.5 } "
      "integrator { kind: EXPLICIT_NEWMARK dt: 0.002 } "
      "substructuring { experimental_dofs { dof: 1 mass: 20 stiffness: 2.0e6 zeta: 0.02 } } "
      "cases { name: \"reference\" } cases { name: \"lag2\" delay { shift { delay: 0.002 } } } "
      "cases { name: \"lag5\" delay { shift { delay: 0.005 } } }";
  return study::prepare_study(study::parse_study(text, "test"), kConfigs);
}

std::vector<const config::Case*> all_cases(const study::PreparedStudy& prepared) {
  std::vector<const config::Case*> cases;
  for (const config::Case& c : prepared.config.cases()) cases.push_back(&c);
  return cases;
}

TEST(CaseSetups, EachLentSetupIsTheCasesOwnWithTheStudysModel) {
  const study::PreparedStudy prepared = frame20();
  CaseSetups setups(prepared, all_cases(prepared), 0.001);
  ASSERT_EQ(setups.loops().size(), 3u);
  for (std::size_t i : {2u, 0u, 1u, 2u}) {
    const config::Case& c = prepared.config.cases(static_cast<int>(i));
    const core::HybridSetup built = study::setup_for_case(prepared, c);
    const core::HybridSetup& lent = setups.lend(i);
    EXPECT_EQ(lent.model.mass, prepared.base.model.mass) << c.name();
    EXPECT_EQ(lent.model.stiffness, prepared.base.model.stiffness) << c.name();
    EXPECT_EQ(lent.model.damping, prepared.base.model.damping) << c.name();
    EXPECT_DOUBLE_EQ(study::answer_lag(lent), study::answer_lag(built)) << c.name();
    EXPECT_EQ(study::case_delay_text(lent), study::case_delay_text(built)) << c.name();
    EXPECT_DOUBLE_EQ(setups.loops()[i].lag, study::answer_lag(built) + 0.001) << c.name();
    EXPECT_EQ(setups.loops()[i].parts.size(), case_loop(built, 0.0).parts.size()) << c.name();
  }
  EXPECT_GT(study::answer_lag(setups.lend(2)), study::answer_lag(setups.lend(1)));
}

TEST(CaseSetups, OneModelIsAliveAtATime) {
  const study::PreparedStudy prepared = frame20();
  CaseSetups setups(prepared, all_cases(prepared), 0.0);
  const core::HybridSetup& first = setups.lend(0);
  EXPECT_EQ(first.model.dofs(), 20);
  const core::HybridSetup& second = setups.lend(1);
  EXPECT_EQ(second.model.dofs(), 20);
  EXPECT_EQ(first.model.dofs(), 0);  // lent on: case 0 holds no model now
  EXPECT_EQ(first.model.mass.size(), 0);
}

}  // namespace
}  // namespace rths::analysis
