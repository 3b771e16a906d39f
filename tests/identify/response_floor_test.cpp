// Never silent on the response (identify/run/response_floor.h), on records of an independent
// closed-loop simulation (independent_record.h): a clean record's re-run stands within its floor,
// the load cell's noise propagated through the re-run; a displacement sensor whose mount creeps
// while the loop follows its reading, invisible on its own channel, leaves a re-run far above
// that floor, which the report says with when and how it grows, the force channel's slow part
// as the travel the specimen missed, and the loop's sensor as the candidate.
#include "identify/run/response_floor.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <string>

#include "identify/run/run_record_format.h"
#include "tests/identify/independent_record.h"

namespace rths::identify {
namespace {

constexpr double kCreep = 1.5e-3;  // m over the record

RunIdentification identify_rig(const std::string& name, const test::RigTruth& rig) {
  RunIdentification run =
      identify_run_record(test::independent_record(name, rig, 15.0), IdentifyOptions{});
  std::printf("%s", run_record_text(run).c_str());
  return run;
}

TEST(ResponseFloorRecords, ACleanRecordsReRunIsAtItsFloor) {
  for (std::uint64_t seed : {7u, 23u}) {
    test::RigTruth rig;
    rig.seed = seed;
    const RunIdentification run = identify_rig("response_floor_clean", rig);
    const auto floor = response_floor(run);
    ASSERT_TRUE(floor.has_value());
    EXPECT_GT(floor->noise_floor, 0.0);
    EXPECT_FALSE(floor->above) << floor->text();
    EXPECT_NE(run_record_text(run).find("at its floor"), std::string::npos);
    EXPECT_TRUE(run_record_json(run)["response_floor"].is_object());
  }
}

TEST(ResponseFloorRecords, ACreepTheLoopFollowsIsNotSilent) {
  test::RigTruth rig;
  rig.followed_creep = kCreep;
  const RunIdentification run = identify_rig("response_floor_creep", rig);
  const auto floor = response_floor(run);
  ASSERT_TRUE(floor.has_value());
  ASSERT_TRUE(floor->above) << floor->text();
  EXPECT_GT(floor->growth, 2.0) << floor->text();
  ASSERT_EQ(floor->force.size(), 1u) << floor->text();
  // The specimen travelled the reading less the creep: the force falls short by k_e x creep.
  EXPECT_NEAR(floor->force.front().as_travel, -kCreep, 0.2 * kCreep) << floor->text();
  const std::string text = run_record_text(run);
  EXPECT_NE(text.find("the re-run's response"), std::string::npos);
  ASSERT_TRUE(floor->silent) << text;  // the load cell's fitted drift is rejected: no name holds it
  {
    EXPECT_NE(text.find("invisible on its own channel"), std::string::npos);
    bool listed = false;
    const nlohmann::json json = run_record_json(run);
    for (const auto& e : json["unexplained"])
      listed = listed || e["part"] == "displacement sensor 1";
    EXPECT_TRUE(listed);
  }
}

}  // namespace
}  // namespace rths::identify
