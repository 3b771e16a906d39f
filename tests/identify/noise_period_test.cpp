// A period in a sensor's noise band (identify/run/noise_period.h), on records of an independent
// closed-loop simulation (independent_record.h): a mains hum on the load cell, too small beside
// the force for the channel's description to report, is described as periodic on the load cell
// at its frequency and amplitude, and the load cell's noise is stated without it; a clean record
// holds no such period.
#include "identify/run/noise_period.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>

#include "identify/run/run_record.h"
#include "identify/run/run_record_format.h"
#include "identify/run/sensors.h"
#include "tests/identify/independent_record.h"

namespace rths::identify {
namespace {

constexpr double kHumHz = 50.0;
constexpr double kHum = 2.5;  // N, beside a force of 260 N RMS

RunIdentification identify_rig(const std::string& name, const test::RigTruth& rig) {
  RunIdentification run =
      identify_run_record(test::independent_record(name, rig, 15.0), IdentifyOptions{});
  std::printf("%s", run_record_text(run).c_str());
  return run;
}

TEST(NoisePeriodRecords, AHumOnTheLoadCellIsPeriodicAndLeftOutOfItsNoise) {
  test::RigTruth rig;
  rig.rattle_force = kHum;
  rig.rattle_frequency = kHumHz;
  rig.rattle_end = 1e9;
  const RunIdentification run = identify_rig("noise_period_hum", rig);
  ASSERT_EQ(run.actuators.size(), 1u);
  const ActuatorPath& path = run.actuators.front();
  // Below the description's share of the force: only the noise band shows it.
  EXPECT_LT(kHum / std::sqrt(2.0), kMinSignalShare * noise_spread(path.id, Channel::kForce));
  const auto u = period_in_noise_band(path, Channel::kForce);
  ASSERT_TRUE(u.has_value()) << run_record_text(run);
  EXPECT_EQ(u->part, "load cell 1");
  ASSERT_TRUE(u->description.periodic.has_value());
  EXPECT_NEAR(u->description.periodic->frequency, kHumHz, 0.05);
  EXPECT_NEAR(u->description.periodic->amplitude, kHum, 0.1 * kHum);
  EXPECT_EQ(u->description.kinds(), std::vector<std::string>{"periodic"});
  // The report holds it, and the load cell's noise is the sensor's own without it.
  const nlohmann::json json = run_record_json(run);
  bool listed = false;
  for (const auto& e : json["unexplained"])
    listed = listed || (e["part"] == "load cell 1" && e["periodic"].is_object() &&
                        std::abs(e["periodic"]["frequency_hz"].get<double>() - kHumHz) < 0.05);
  EXPECT_TRUE(listed) << json["unexplained"].dump(1);
  EXPECT_LT(path.force_noise, 1.2 * rig.force_noise) << run_record_text(run);
  EXPECT_NE(u->text().find("without it"), std::string::npos) << u->text();
}

TEST(NoisePeriodRecords, ACleanRecordHoldsNoPeriodInItsNoiseBand) {
  for (std::uint64_t seed : {7u, 11u}) {
    test::RigTruth rig;
    rig.seed = seed;
    const RunIdentification run = identify_rig("noise_period_clean", rig);
    for (Channel channel : {Channel::kMeasured, Channel::kForce})
      EXPECT_FALSE(period_in_noise_band(run.actuators.front(), channel).has_value())
          << "seed " << seed;
  }
}

}  // namespace
}  // namespace rths::identify
