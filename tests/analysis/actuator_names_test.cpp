#include "analysis/study_run/actuator_names.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "study/study.h"

namespace rths::analysis {
namespace {

const std::filesystem::path kConfigs = std::filesystem::path(RTHS_SOURCE_DIR) / "configs";

// A 3-DOF frame whose specimens the config lists as DOF 3, DOF 1, then the storey-2 element:
// their channels (actuator indices) are DOF 1, DOF 3, element 1.
study::PreparedStudy frame(const std::string& deployment) {
  const std::string text =
      "name: \"frame3\" structure { matrices { "
      "mass { rows: 3 values: [1000, 0, 0, 0, 1000, 0, 0, 0, 800] } "
      "stiffness { rows: 3 values: [4e6, -2e6, 0, -2e6, 3.5e6, -1.5e6, 0, -1.5e6, 1.5e6] } } "
      "damping { modal_zeta: 0.05 } } "
      "motion { path: \"../data/ground_motions/RSN175_IMPVALL.H_H-E12140.AT2\" duration: 1 } "
      "integrator { dt: 0.001 } "
      "substructuring { experimental_dofs { dof: 3 stiffness: 1e5 } "
      "experimental_dofs { dof: 1 stiffness: 1e5 } "
      "experimental_dofs { dof: 2 from_dof: 1 stiffness: 1e5 } } "
      "cases { name: \"reference\" } " +
      deployment;
  return study::prepare_study(study::parse_study(text, "test"), kConfigs);
}

TEST(ActuatorNames, ActuatorsAreListedInConfigOrderAndNamedByTheirSite) {
  const study::PreparedStudy prepared = frame(
      "deployment { nodes { id: 1 kind: SUBSTRUCTURE site: \"site_a\" } "
      "nodes { id: 2 kind: ACTUATOR_EMULATOR storeys: 3 site: \"lab_c\" } "
      "nodes { id: 3 kind: ACTUATOR_EMULATOR storeys: 1 storeys: 4 site: \"lab_b\" } }");
  ASSERT_EQ(prepared.base.partition.actuator_storeys, (std::vector<int>{0, 2, 3}));
  const ActuatorNames names = actuator_names(prepared.config, prepared.base.partition);
  EXPECT_EQ(names.order, (std::vector<int>{1, 0, 2}));
  EXPECT_EQ(names.of(1), "lab_c");
  // lab_b hosts two actuators: each keeps its channel beside the site.
  EXPECT_EQ(names.of(0), "lab_b, DOF 1");
  EXPECT_EQ(names.of(2).rfind("lab_b, element 1 (", 0), 0u) << names.of(2);
  EXPECT_EQ(names.of(7), "actuator 8");
}

TEST(ActuatorNames, WithoutSitesTheChannelNamesEachActuator) {
  const study::PreparedStudy prepared = frame("");
  const ActuatorNames names = actuator_names(prepared.config, prepared.base.partition);
  EXPECT_EQ(names.order, (std::vector<int>{1, 0, 2}));
  EXPECT_EQ(names.of(0), "DOF 1");
  EXPECT_EQ(names.of(1), "DOF 3");
  EXPECT_EQ(names.of(2).rfind("element 1 (", 0), 0u) << names.of(2);
}

}  // namespace
}  // namespace rths::analysis
