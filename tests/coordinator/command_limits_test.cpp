// CommandLimits: each limit trips with a message naming what and by how much, 0 turns a limit off,
// NaN never passes, and the rate limit compares with the last drift that passed.
#include "coordinator/command_limits.h"

#include <gtest/gtest.h>

#include <cmath>

namespace rths::coordinator {
namespace {

config::SafetyLimits limits(double displacement, double velocity, double step) {
  config::SafetyLimits l;
  l.set_max_displacement(displacement);
  l.set_max_velocity(velocity);
  l.set_max_displacement_step(step);
  return l;
}

core::Vec vec(std::initializer_list<double> values) {
  core::Vec v(static_cast<Eigen::Index>(values.size()));
  Eigen::Index i = 0;
  for (double x : values) v[i++] = x;
  return v;
}

TEST(CommandLimits, DisplacementAndVelocityTripPerDofAndNameIt) {
  const CommandLimits c(limits(0.1, 2.0, 0.0), {0}, 2);
  EXPECT_FALSE(c.check_state(vec({0.1, -0.1}), vec({2.0, -2.0})).has_value())
      << "at the limit passes";
  const auto u = c.check_state(vec({0.0, -0.15}), vec({0.0, 0.0}));
  ASSERT_TRUE(u.has_value());
  EXPECT_NE(u->find("|u| of DOF 2 = -0.150000 m exceeds 0.100000 m; command not sent"),
            std::string::npos)
      << *u;
  const auto v = c.check_state(vec({0.0, 0.0}), vec({2.5, 0.0}));
  ASSERT_TRUE(v.has_value());
  EXPECT_NE(v->find("|v| of DOF 1 = 2.500000 m/s exceeds 2.000000 m/s"), std::string::npos) << *v;
  EXPECT_TRUE(c.check_state(vec({NAN, 0.0}), vec({0.0, 0.0})).has_value()) << "NaN must not pass";
}

TEST(CommandLimits, ZeroTurnsALimitOff) {
  CommandLimits c(limits(0.0, 0.0, 0.0), {0}, 1);
  EXPECT_FALSE(c.check_state(vec({1e6}), vec({1e6})).has_value());
  EXPECT_FALSE(c.check_rate(vec({1e6})).has_value());
}

TEST(CommandLimits, RateLimitComparesWithTheLastDriftThatPassedOnActuatorStoreysOnly) {
  CommandLimits c(limits(0.0, 0.0, 0.002), {1}, 2);
  EXPECT_FALSE(c.check_rate(vec({0.5, 0.002})).has_value()) << "storey 1 carries no actuator";
  EXPECT_FALSE(c.check_rate(vec({0.0, 0.004})).has_value());
  const auto jump = c.check_rate(vec({0.0, 0.0065}));
  ASSERT_TRUE(jump.has_value());
  EXPECT_NE(jump->find("commanded drift of storey 2 changes by 0.002500 m in one step (limit "
                       "0.002000 m per step); command not sent"),
            std::string::npos)
      << *jump;
  EXPECT_FALSE(c.check_rate(vec({0.0, 0.0055})).has_value())
      << "the refused drift must not become the previous one";
  EXPECT_TRUE(c.check_rate(vec({0.0, NAN})).has_value());
}

}  // namespace
}  // namespace rths::coordinator
