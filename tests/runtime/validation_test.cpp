#include "runtime/validation.h"

#include <gtest/gtest.h>

#include <cmath>

#include "runtime/schema.h"

namespace rths::runtime {
namespace {

constexpr char kRun[] = "run-7";

TEST(CheckEnvelope, AcceptsThisRunsKnownKinds) {
  EXPECT_EQ(check_envelope(pack(kRun, 1, FEEDBACK, 4, Feedback{}), kRun), Verdict::kAccept);
}

TEST(CheckEnvelope, RejectsAnotherRun) {
  EXPECT_EQ(check_envelope(pack("run-8", 1, FEEDBACK, 4, Feedback{}), kRun), Verdict::kForeignRun);
  EXPECT_EQ(check_envelope(pack("", 1, FEEDBACK, 4, Feedback{}), kRun), Verdict::kForeignRun);
}

TEST(CheckEnvelope, RejectsUnknownKinds) {
  auto m = pack(kRun, 1, FEEDBACK, 4, Feedback{});
  m.kind = 999;
  EXPECT_EQ(check_envelope(m, kRun), Verdict::kGarbage);
  m.kind = MESSAGE_KIND_UNSPECIFIED;
  EXPECT_EQ(check_envelope(m, kRun), Verdict::kGarbage);
}

TEST(CheckStep, OrdersSteps) {
  EXPECT_EQ(check_step(5, 4, 5), Verdict::kAccept);
  EXPECT_EQ(check_step(4, 4, 5), Verdict::kDuplicate);
  EXPECT_EQ(check_step(2, 4, 5), Verdict::kStale);
  EXPECT_EQ(check_step(9, 4, 5), Verdict::kOutOfOrder);
}

TEST(Unpack, GarbageBytesDoNotParse) {
  auto m = pack(kRun, 1, COMMAND, 1, Command{});
  m.payload = "\xff\xff\xff\xff";
  Command c;
  EXPECT_FALSE(unpack(m, c));
}

TEST(Unpack, DoublesCrossBitForBit) {
  Command c;
  c.add_drift(0.1 + 0.2);  // not representable exactly in decimal
  c.add_drift(-0.0);
  Command back;
  ASSERT_TRUE(unpack(pack(kRun, 1, COMMAND, 1, c), back));
  EXPECT_EQ(back.drift(0), 0.1 + 0.2);
  EXPECT_TRUE(std::signbit(back.drift(1)));
}

TEST(RejectCounters, CountsEachVerdictOnce) {
  RejectCounters counters;
  for (Verdict v : {Verdict::kForeignRun, Verdict::kGarbage, Verdict::kDuplicate, Verdict::kStale,
                    Verdict::kOutOfOrder, Verdict::kUnknownNode, Verdict::kAccept})
    counters.count(v);
  EXPECT_EQ(counters.total(), 6u);
  Counters c;
  counters.fill(c);
  EXPECT_EQ(c.foreign_run(), 1u);
  EXPECT_EQ(c.out_of_order(), 1u);
}

}  // namespace
}  // namespace rths::runtime
