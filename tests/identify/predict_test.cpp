#include "identify/lab/predict.h"

#include <gtest/gtest.h>

#include <filesystem>

namespace rths::identify {
namespace {

const std::filesystem::path kPaperFrame =
    std::filesystem::path(RTHS_SOURCE_DIR) / "configs/paper_frame.textproto";

SignalScales scales() { return SignalScales{}; }

ChannelModel pure_delay(double delay) {
  ChannelModel m = declared_model(Channel::kMeasured, {Effect::kDelay}, scales());
  m.params = {1.0, delay};
  return m;
}

TEST(PredictTest, ChainCarriesTheFittedDynamics) {
  ChannelModel m = pure_delay(0.005);
  m = with_effect(m, Effect::kFirstOrder, std::vector<double>{0.02});
  m = with_effect(m, Effect::kOffsetDrift, std::vector<double>{1e-4, 0.0});
  const ActuatorChain chain = actuator_chain(m, scales(), 0.001);
  EXPECT_NEAR(chain.chain.nominal_delay(), 0.025, 1e-9);
  ASSERT_EQ(chain.ignored.size(), 1u);
  EXPECT_NE(chain.ignored[0].find("offset_drift"), std::string::npos);
  const ChannelModel force = declared_model(Channel::kForce, {Effect::kStiffness}, scales());
  EXPECT_THROW(actuator_chain(force, scales(), 0.001), std::invalid_argument);
}

TEST(PredictTest, A14msPureDelayReproducesThePaperCase) {
  const StudyPrediction p = predict_study(kPaperFrame, pure_delay(0.014), scales());
  const CaseError* shift = nullptr;
  for (const auto& c : p.cases) {
    if (c.name == "lag_shift_14ms") shift = &c;
  }
  ASSERT_NE(shift, nullptr);
  EXPECT_NEAR(p.identified.nrmse, shift->nrmse, 1e-12);
  EXPECT_NEAR(p.identified.paper_eq2, shift->paper_eq2, 1e-12);
  EXPECT_GT(p.identified.nrmse, 0.0);
}

TEST(PredictTest, MoreLagPredictsALargerError) {
  const StudyPrediction small = predict_study(kPaperFrame, pure_delay(0.005), scales());
  ChannelModel slow = pure_delay(0.005);
  slow = with_effect(slow, Effect::kFirstOrder, std::vector<double>{0.015});
  const StudyPrediction large = predict_study(kPaperFrame, slow, scales());
  EXPECT_GT(large.identified.nrmse, small.identified.nrmse);
  EXPECT_NEAR(large.identified.nominal_delay, 0.020, 1e-9);
}

TEST(PredictTest, MissingConfigIsAnError) {
  EXPECT_ANY_THROW(predict_study("/nonexistent/study.textproto", pure_delay(0.01), scales()));
}

}  // namespace
}  // namespace rths::identify
