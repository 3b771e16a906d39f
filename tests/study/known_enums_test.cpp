// require_known_enums (study/known_enums.h): a number an enum does not name is refused with its
// field path, in a study as loaded, nested and repeated fields included.
#include "study/known_enums.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "study/study.h"

namespace rths::study {
namespace {

using testing::HasSubstr;

const std::string kStudy =
    "name: \"enums\"\n"
    "structure { sdof { period: 0.5 mass: 1000 } damping { modal_zeta: 0.05 } }\n"
    "motion { path: \"x.at2\" }\n"
    "substructuring { experimental_fraction: 0.5 }\n"
    "cases { name: \"reference\" }\n";

std::string refusal(const std::string& text) {
  try {
    parse_study(text, "study.textproto");
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "(accepted)";
}

TEST(KnownEnums, AnIntegratorKindNobodyNamedIsRefusedNotRunAsNewmark) {
  EXPECT_THAT(refusal(kStudy + "integrator { kind: 77 }"),
              HasSubstr("study.textproto: integrator.kind: 77 is not a known value "
                        "(EXPLICIT_NEWMARK, CENTRAL_DIFFERENCE"));
  config::Integrator integrator;
  integrator.set_kind(static_cast<config::Integrator::Kind>(77));
  EXPECT_THROW(integrator_kind(integrator), std::invalid_argument);
}

TEST(KnownEnums, NestedAndRepeatedFieldsAreNamedByTheirPath) {
  EXPECT_THAT(refusal(kStudy + "deployment { nodes { id: 1 kind: 9 } }"),
              HasSubstr("deployment.nodes[0].kind: 9 is not a known value"));
  EXPECT_THAT(refusal(kStudy + "deployment { clock: 5 }"),
              HasSubstr("deployment.clock: 5 is not a known value"));
}

TEST(KnownEnums, KnownValuesPass) {
  config::Study study;
  study.mutable_integrator()->set_kind(config::Integrator::CHEN_RICLES);
  study.mutable_deployment()->add_nodes()->set_kind(config::NodeSpec::ACTUATOR_EMULATOR);
  EXPECT_NO_THROW(require_known_enums(study, "study"));
  study.mutable_deployment()->mutable_nodes(0)->set_kind(static_cast<config::NodeSpec::Kind>(42));
  EXPECT_THROW(require_known_enums(study, "study"), std::invalid_argument);
}

}  // namespace
}  // namespace rths::study
