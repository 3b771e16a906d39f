#include "study/recorders.h"

#include <gtest/gtest.h>

#include <stdexcept>
#include <string>
#include <vector>

#include "study/study.h"

namespace rths::study {
namespace {

using Kind = RecordedChannel::Kind;

// A study of a two-floor shear building with the given recorders blocks (text format).
config::Study study_with(const std::string& recorders) {
  return parse_study(
      "structure { shear_building { storey_mass: [1000, 1000] storey_stiffness: [4e5, 3e5] } }\n"
      "motion { path: \"m.txt\" column_dt: 0.01 }\n"
      "substructuring { experimental_storeys: 1 }\n" +
          recorders,
      "test.textproto");
}

std::string load_error(const std::string& recorders) {
  try {
    study_with(recorders);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

std::string plan_error(const std::string& recorders, int dofs) {
  try {
    plan_recorders(study_with(recorders), dofs, {0});
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

std::vector<int> dofs_of(const RecorderPlan& plan, Kind kind) {
  std::vector<int> out;
  for (const RecordedChannel& c : plan.channels)
    if (c.kind == kind) out.push_back(c.dof);
  return out;
}

TEST(RecordersTest, ASmallModelKeepsEveryDofAndEveryActuatorByDefault) {
  const RecorderPlan plan = plan_recorders(study_with(""), 3, {0});
  EXPECT_TRUE(plan.kept_dofs.empty());
  EXPECT_TRUE(plan.defaults.empty());
  EXPECT_EQ(dofs_of(plan, Kind::kDisplacement), (std::vector<int>{0, 1, 2}));
  EXPECT_EQ(dofs_of(plan, Kind::kActuators), (std::vector<int>{-1}));
  EXPECT_FALSE(plan.base_shear);
}

TEST(RecordersTest, ALargeModelKeepsAStatedHandfulByDefaultAndSaysWhich) {
  const RecorderPlan plan = plan_recorders(study_with(""), 1000, {499, 500});
  EXPECT_EQ(dofs_of(plan, Kind::kDisplacement), (std::vector<int>{0, 249, 499, 500, 749, 999}));
  EXPECT_EQ(plan.kept_dofs, (std::vector<int>{0, 249, 499, 500, 749, 999}));
  EXPECT_NE(plan.defaults.find("1000 DOFs"), std::string::npos) << plan.defaults;
  EXPECT_NE(plan.defaults.find("DOFs 1, 250, 500, 501, 750, 1000"), std::string::npos)
      << plan.defaults;
}

TEST(RecordersTest, RecordersKeepWhatTheyNameAndTheRunKeepsTheTopAndTheExperimentalDofs) {
  const RecorderPlan plan = plan_recorders(
      study_with(
          "recorders { dofs: 10 ranges { first: 100 last: 130 step: 10 } "
          "quantities: [VELOCITY, ACCELERATION] every: 4 }\n"
          "recorders { drifts { dof: 7 from_dof: 6 } drifts { dof: 2 } base_shear: true }\n"),
      500, {0});
  EXPECT_EQ(dofs_of(plan, Kind::kVelocity), (std::vector<int>{9, 99, 109, 119, 129}));
  EXPECT_EQ(dofs_of(plan, Kind::kAcceleration), (std::vector<int>{9, 99, 109, 119, 129}));
  EXPECT_TRUE(dofs_of(plan, Kind::kDisplacement).empty());
  EXPECT_TRUE(dofs_of(plan, Kind::kActuators).empty());
  EXPECT_EQ(dofs_of(plan, Kind::kDrift), (std::vector<int>{6, 1}));
  EXPECT_TRUE(plan.base_shear);
  EXPECT_TRUE(plan.defaults.empty());
  EXPECT_EQ(plan.kept_dofs, (std::vector<int>{0, 1, 5, 6, 9, 99, 109, 119, 129, 499}));
  EXPECT_EQ(plan.channels.front().every, 4);
  EXPECT_TRUE(plan.keeps(0));
  EXPECT_TRUE(plan.keeps(3));  // the drifts and base shear keep every step
}

TEST(RecordersTest, AChannelAskedTwiceKeepsTheStepsOfBoth) {
  const RecorderPlan plan = plan_recorders(
      study_with("recorders { dofs: 2 every: 2 }\nrecorders { dofs: 2 every: 3 }\n"), 2, {0});
  ASSERT_EQ(plan.channels.size(), 1u);
  EXPECT_EQ(plan.channels[0].every, 1);
  const RecorderPlan even = plan_recorders(
      study_with("recorders { dofs: 1 every: 4 }\nrecorders { dofs: 1 every: 6 }\n"), 2, {0});
  EXPECT_EQ(even.channels.at(0).every, 2);
  EXPECT_TRUE(even.keeps(4));
  EXPECT_FALSE(even.keeps(3));
}

TEST(RecordersTest, ADofPastTheModelIsRefusedNamingTheFieldAndTheDof) {
  EXPECT_EQ(plan_error("recorders { dofs: [1, 2, 1001] }", 1000),
            "recorders[0].dofs[2]: DOF 1001 is outside the model's 1..1000");
  EXPECT_NE(
      plan_error("recorders { experimental: true }\nrecorders { ranges { first: 1 last: 3 } }", 2)
          .find("recorders[1].ranges[0].last: DOF 3"),
      std::string::npos);
  EXPECT_NE(plan_error("recorders { drifts { dof: 2 from_dof: 9 } }", 2)
                .find("recorders[0].drifts[0].from_dof: DOF 9"),
            std::string::npos);
}

TEST(RecordersTest, BadRecordersAreRefusedAtLoadNamingTheField) {
  EXPECT_NE(load_error("recorders { every: 2 }").find("recorders[0]. asks for nothing"),
            std::string::npos);
  EXPECT_NE(load_error("recorders { dofs: 0 }").find("recorders[0].dofs[0] must be a DOF >= 1"),
            std::string::npos);
  EXPECT_NE(load_error("recorders { ranges { first: 5 last: 2 } }")
                .find("recorders[0].ranges[0] must have 1 <= first <= last"),
            std::string::npos);
  EXPECT_NE(load_error("recorders { drifts { dof: 3 from_dof: 3 } }")
                .find("recorders[0].drifts[0] must join two different DOFs"),
            std::string::npos);
  EXPECT_NE(load_error("recorders { dofs: 1 every: -1 }").find("recorders[0].every must be >= 0"),
            std::string::npos);
  EXPECT_NE(load_error("recorders { experimental: true quantities: VELOCITY }")
                .find("recorders[0].quantities applies to dofs and ranges"),
            std::string::npos);
  EXPECT_EQ(load_error("recorders { dofs: 1 }"), "");
}

TEST(RecordersTest, ARunsBytesPerStepCountItsSimulationsTableAndMotion) {
  // One DOF, one actuator, two cases: three simulations of 8 + 24 + 32 bytes, two responses,
  // a table of step, time and four columns a case, the motion twice.
  const RecorderPlan sdof = plan_recorders(study_with(""), 1, {0});
  EXPECT_EQ(sdof.columns_per_case(1), 4u);
  EXPECT_EQ(run_bytes_per_step(sdof, 1, 1, 2, false), 3u * 64 + 2 * 8 + 8 * (2 + 2 * 4) + 16);
  EXPECT_EQ(run_bytes_per_step(sdof, 1, 1, 2, true) - run_bytes_per_step(sdof, 1, 1, 2, false),
            3u * 24);
  // 10,000 DOFs: the default recorders keep 6 DOFs, so a step costs hundreds of bytes, not the
  // 240,000 a simulation of every DOF would.
  const RecorderPlan large = plan_recorders(study_with(""), 10000, {0});
  EXPECT_LT(run_bytes_per_step(large, 10000, 1, 2, false), 1000u);
}

TEST(RecordersTest, ExperimentalDofsAreTheStoreysFloorsOrTheElementsTerms) {
  core::HybridPartition storeys;
  storeys.numerical.resize(3);
  storeys.experimental.resize(3);
  storeys.actuator_storeys = {2};
  EXPECT_EQ(experimental_dofs(storeys), (std::vector<int>{1, 2}));
  core::HybridPartition by_dofs;
  by_dofs.by_dofs = true;
  by_dofs.numerical.resize(4);
  by_dofs.experimental.resize(4);
  by_dofs.elements.push_back({{{2, 1.0}, {0, -1.0}}});
  by_dofs.actuator_storeys = {1, 3};
  EXPECT_EQ(experimental_dofs(by_dofs), (std::vector<int>{0, 1, 2}));
}

// The coordinator's loop and rths run keep the same per-step state: what the plan keeps, and the
// peaks over every DOF only where a limit is judged on them.
TEST(RecordersTest, TheSimulationKeepsThePlansDofsAndBaseShearAndPeaksOnlyUnderALimit) {
  const RecorderPlan plan =
      plan_recorders(study_with("recorders { dofs: [300] base_shear: true }\n"), 1000, {0});
  config::SafetyLimits limits;
  core::SimulationOptions options = kept_by_recorders(plan, limits);
  EXPECT_EQ(options.kept_dofs, (std::vector<int>{0, 299, 999}));
  EXPECT_TRUE(options.base_shear);
  EXPECT_FALSE(options.peaks);
  limits.set_max_velocity(2.0);
  EXPECT_TRUE(kept_by_recorders(plan, limits).peaks);
  limits = {};
  limits.set_max_displacement(0.1);
  EXPECT_TRUE(kept_by_recorders(plan, limits).peaks);
  const RecorderPlan small = plan_recorders(study_with(""), 3, {0});
  options = kept_by_recorders(small, {});
  EXPECT_TRUE(options.kept_dofs.empty());
  EXPECT_FALSE(options.base_shear);
}

}  // namespace
}  // namespace rths::study
