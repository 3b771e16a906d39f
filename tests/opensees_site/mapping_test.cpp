#include "opensees_site/mapping.h"

#include <gtest/gtest.h>

namespace rths::opensees {
namespace {

config::OpenSeesSite site(int n, std::vector<double> t, std::vector<double> k = {}) {
  config::OpenSeesSite s;
  s.set_basic_dofs(n);
  for (double x : t) s.add_transformation(x);
  for (double x : k) s.add_initial_stiffness(x);
  return s;
}

TEST(BasicMapping, OneActuatorOnTheRelativeDisplacementOfTwoNodes) {
  const BasicMapping m(site(2, {-1, 1}), {5000.0}, {0}, 1);
  const double basic[2] = {0.001, 0.004};
  core::Vec drift, u = core::Vec::Zero(1);
  m.to_floors(basic, drift, u);
  EXPECT_DOUBLE_EQ(u[0], 0.003);
  double force[2];
  m.to_basic(core::Vec::Constant(1, 15.0), force);
  EXPECT_EQ(force[0], -15.0);
  EXPECT_EQ(force[1], 15.0);
  EXPECT_EQ(m.stiffness()(0, 0), 5000.0);
  EXPECT_EQ(m.stiffness()(0, 1), -5000.0);
}

TEST(BasicMapping, IdentityOnTwoStoreysGivesFloorsFromDrifts) {
  const BasicMapping m(site(0, {}), {1.0, 2.0}, {0, 1}, 2);
  const double basic[2] = {0.01, 0.02};
  core::Vec drift, u = core::Vec::Zero(2);
  m.to_floors(basic, drift, u);
  EXPECT_DOUBLE_EQ(u[0], 0.01);
  EXPECT_DOUBLE_EQ(u[1], 0.03);
}

TEST(BasicMapping, DeclaredStiffnessIsColumnMajor) {
  const BasicMapping m(site(2, {-1, 1}, {1, 2, 3, 4}), {5000.0}, {0}, 1);
  EXPECT_EQ(m.stiffness()(1, 0), 2.0);
  EXPECT_EQ(m.stiffness()(0, 1), 3.0);
}

TEST(BasicMapping, BadMappingsNameTheField) {
  EXPECT_THROW(BasicMapping(site(2, {}), {1.0}, {0}, 1), std::invalid_argument);
  EXPECT_THROW(BasicMapping(site(2, {1, 2, 3}), {1.0}, {0}, 1), std::invalid_argument);
  EXPECT_THROW(BasicMapping(site(2, {-1, 1}, {1, 2}), {1.0}, {0}, 1), std::invalid_argument);
  EXPECT_THROW(BasicMapping(site(-1, {}), {1.0}, {0}, 1), std::invalid_argument);
  try {
    BasicMapping(site(2, {-1, NAN}), {1.0}, {0}, 1);
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("deployment.opensees.transformation[1]"),
              std::string::npos);
  }
}

}  // namespace
}  // namespace rths::opensees
