#include "runtime/node/validation.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "runtime/node/schema.h"

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

TEST(CheckEnvelope, AnEmptyRunIdIsNeverThisRuns) {
  EXPECT_EQ(check_envelope(pack("", 1, ANNOUNCE, 0, Announce{}), ""), Verdict::kForeignRun);
}

TEST(CheckSender, TheNodesOwnTopicAndOncePinnedItsOwnWriter) {
  auto m = pack(kRun, 2, HOLD, 4, Hold{});
  EXPECT_EQ(check_sender(m, 0), Verdict::kAccept) << "pack stamps the node's own topic";
  m.topic_node = 1;
  EXPECT_EQ(check_sender(m, 0), Verdict::kNotEntitled) << "node 2's id on node 1's topic";
  m.topic_node = 2;
  m.writer = 11;
  EXPECT_EQ(check_sender(m, 11), Verdict::kAccept);
  EXPECT_EQ(check_sender(m, 12), Verdict::kNotEntitled);
  m.writer = 0;
  EXPECT_EQ(check_sender(m, 12), Verdict::kAccept) << "no writer identity: not checked";
}

TEST(FiniteWithin, RejectsNonFiniteAndBeyondTheLimit) {
  EXPECT_TRUE(finite_within(std::vector<double>{0.1, -0.2}, 0.2));
  EXPECT_FALSE(finite_within(std::vector<double>{0.1, -0.21}, 0.2));
  EXPECT_TRUE(finite_within(std::vector<double>{1e300}, 0.0)) << "no limit: finite only";
  EXPECT_FALSE(finite_within(std::vector<double>{std::nan("")}, 0.0));
  EXPECT_FALSE(finite_within(std::vector<double>{-INFINITY}, 0.0));
}

TEST(RejectCounters, CountsEveryCauseAndRoundTripsThroughCounters) {
  RejectCounters r;
  for (const Verdict v :
       {Verdict::kForeignRun, Verdict::kGarbage, Verdict::kDuplicate, Verdict::kStale,
        Verdict::kOutOfOrder, Verdict::kUnknownNode, Verdict::kNotEntitled, Verdict::kOutOfRange})
    r.count(v);
  EXPECT_EQ(r.total(), 8u);
  Counters c;
  r.fill(c);
  EXPECT_EQ(c.not_entitled(), 1u);
  EXPECT_EQ(c.out_of_range(), 1u);
  EXPECT_EQ(RejectCounters::from(c).total(), 8u);
  EXPECT_EQ(to_string(Verdict::kNotEntitled), "not entitled");
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
