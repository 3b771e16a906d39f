// One verdict over every part (identify/run/findings.h), the rule on a delay longer one way: a
// fitted delay 7.6 ms above the declared 14 ms whose measured channel's residual leads 7.8 ms more
// rising than falling is two delays, not one that changed: the "delay change" finding leaves the
// named list and the description says about 17.7 ms rising and 25.5 ms falling; every section
// says the same (the actuator's section and the re-run's share name no delay change). A lead
// difference under half the change (a delay that changed, with a little asymmetry) leaves the
// finding named everywhere.
#include "identify/run/findings.h"

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "identify/run/run_record_format.h"
#include "identify/run/unexplained.h"

namespace rths::identify {
namespace {

struct Case {
  std::vector<ActuatorPath> paths;
  std::vector<Unexplained> unexplained;
  std::vector<Finding> findings;
  RunResidual residual;
};

// A path whose delay went 14 -> 21.6 ms, named, and its measured channel described with a lead
// `lead_difference` (s) larger rising than falling.
Case lag_case(double lead_difference) {
  Case out;
  ActuatorPath path;
  path.actuator = 1;
  path.declared_delay = 0.014;
  path.fitted_delay = 0.0216;
  path.undeclared = {"delay change"};
  out.paths.push_back(path);
  Unexplained u;
  u.actuator = 1;
  u.channel = Channel::kMeasured;
  u.part = "actuator 1";
  u.channel_word = "displacement";
  u.unit = "m";
  DirectionSignature direction;
  direction.of_rate = true;
  direction.explained = 0.97;
  direction.lead_difference = lead_difference;
  u.description.direction = direction;
  out.unexplained.push_back(u);
  Finding f;
  f.part = "actuator 1";
  f.effect = "delay change";
  out.findings.push_back(f);
  out.residual.effects.push_back({"actuator 1", "delay change", 1.03, 1.0});
  return out;
}

// The report of the case after describe_direction_delays, as `rths identify` prints it.
std::string report_of(const Case& c) {
  RunIdentification run;
  run.actuators = c.paths;
  run.unexplained = c.unexplained;
  run.findings = c.findings;
  run.residual = c.residual;
  return run_record_text(run);
}

TEST(Findings, ADelayLongerOneWayIsDescribedNotNamedAsADelayChange) {
  Case c = lag_case(0.0078);
  describe_direction_delays(c.paths, c.unexplained, c.findings, &c.residual);
  EXPECT_TRUE(c.findings.empty());
  EXPECT_TRUE(c.paths[0].undeclared.empty());
  ASSERT_EQ(c.paths[0].not_named.size(), 1u);
  EXPECT_EQ(c.paths[0].not_named[0].effect, "delay change");
  EXPECT_EQ(c.residual.effects[0].effect, kDelaysByDirection);
  const std::string report = report_of(c);
  EXPECT_EQ(report.find("undeclared effects: delay change"), std::string::npos) << report;
  EXPECT_EQ(report.find("delay change removes"), std::string::npos) << report;
  EXPECT_NE(report.find("  delay: a delay that differs by the direction of motion"),
            std::string::npos)
      << report;
  ASSERT_EQ(c.unexplained.at(0).notes.size(), 1u);
  const std::string text = c.unexplained[0].text();
  EXPECT_NE(text.find("a delay that differs by the direction of motion: about 17.7 ms rising, "
                      "25.5 ms falling (declared 14 ms; the re-run holds their mean 21.6 ms)"),
            std::string::npos)
      << text;
  EXPECT_EQ(c.unexplained[0].json()["notes"].size(), 1u);
}

TEST(Findings, ADelayThatChangedWithALittleAsymmetryStaysNamed) {
  Case c = lag_case(0.002);
  describe_direction_delays(c.paths, c.unexplained, c.findings, &c.residual);
  ASSERT_EQ(c.findings.size(), 1u);
  EXPECT_EQ(c.findings[0].effect, "delay change");
  EXPECT_EQ(c.paths[0].undeclared, std::vector<std::string>{"delay change"});
  EXPECT_EQ(c.residual.effects[0].effect, "delay change");
  EXPECT_TRUE(c.paths[0].delay_by_direction.empty());
  EXPECT_TRUE(c.unexplained.at(0).notes.empty());
}

}  // namespace
}  // namespace rths::identify
