#include "identify/lab/report.h"

#include <gtest/gtest.h>

#include "identify/lab/generator.h"

namespace rths::identify {
namespace {

Identification generated(bool with_effect) {
  GeneratorSpec spec;
  spec.duration = 12.0;
  if (with_effect) spec.first_order_time_constant = 0.015;
  IdentifyOptions options;
  options.channels = {Channel::kMeasured, Channel::kForce};
  return identify(generate_measured(spec), options);
}

TEST(ReportTest, JsonStepsCarryTheContractFields) {
  const Identification id = generated(true);
  const auto json = to_json(id, ReportContext{});
  ASSERT_TRUE(json.contains("steps"));
  ASSERT_GE(json["steps"].size(), 1u);
  const auto& step = json["steps"][0];
  for (const char* key : {"channel", "effect", "params", "train_error_before", "train_error_after",
                          "heldout_error_before", "heldout_error_after"}) {
    EXPECT_TRUE(step.contains(key)) << key;
  }
  EXPECT_EQ(step["channel"], "measured");
  EXPECT_EQ(step["effect"], "first_order");
  EXPECT_NEAR(step["params"]["time_constant"]["value"].get<double>(), 0.015, 5e-4);
  EXPECT_GT(step["params"]["time_constant"]["std_error"].get<double>(), 0.0);
  EXPECT_LT(step["heldout_error_after"].get<double>(), step["heldout_error_before"].get<double>());
  EXPECT_EQ(json["channels"].size(), 2u);
}

TEST(ReportTest, CleanDataGivesAnEmptyStepList) {
  const Identification id = generated(false);
  const auto json = to_json(id, ReportContext{});
  EXPECT_TRUE(json["steps"].is_array());
  EXPECT_TRUE(json["steps"].empty());
  EXPECT_NE(format_table(id).find("nothing added"), std::string::npos);
}

TEST(ReportTest, TableNamesTheAddedEffectAndItsParameters) {
  const Identification id = generated(true);
  const std::string table = format_table(id);
  EXPECT_NE(table.find("+ first_order"), std::string::npos);
  EXPECT_NE(table.find("time_constant"), std::string::npos);
}

}  // namespace
}  // namespace rths::identify
