// The answers the loop used, from a record's link samples (platform_replay.h), spread to the
// sources each node answers for as the coordinator plans the run (runtime/node/answer_sources.h):
// a study that declares no nodes runs on its default ones (node 1 the substructure, node 2 the
// actuator emulator), and its record's late answers are replayed on them.
#include <gtest/gtest.h>

#include <memory>
#include <vector>

#include "identify/run/platform_replay.h"
#include "runtime/node/answer_sources.h"
#include "study/study.h"
#include "tests/runtime/test_support.h"

namespace rths::identify {
namespace {

// Step records whose link to each node answered the steps in `answered` (node id -> per step).
std::vector<std::unique_ptr<runtime::StepRecord>> steps_answering(
    const std::vector<std::pair<int, std::vector<std::int64_t>>>& answered, std::size_t count) {
  std::vector<std::unique_ptr<runtime::StepRecord>> out;
  for (std::size_t k = 0; k < count; ++k) {
    auto step = std::make_unique<runtime::StepRecord>();
    for (const auto& [node, steps] : answered) {
      runtime::LinkSample* link = step->add_links();
      link->set_node_id(node);
      link->set_answered_step(steps[k]);
    }
    out.push_back(std::move(step));
  }
  return out;
}

std::vector<const runtime::StepRecord*> pointers(
    const std::vector<std::unique_ptr<runtime::StepRecord>>& steps) {
  std::vector<const runtime::StepRecord*> out;
  for (const auto& s : steps) out.push_back(s.get());
  return out;
}

TEST(PlatformReplay, AStudyWithoutNodesIsReplayedOnItsDefaultNodes) {
  const config::Study study = study::parse_study(test::paper_frame_study(1.0, ""), "test");
  const std::vector<runtime::NodeSources> nodes = runtime::answer_sources(study, 0.001, ".");
  ASSERT_EQ(nodes.size(), 2u);
  EXPECT_EQ(nodes[0].node_id, 1);
  EXPECT_TRUE(nodes[0].numerical);
  EXPECT_EQ(nodes[0].sources, std::vector<int>{0});
  EXPECT_EQ(nodes[1].node_id, 2);
  EXPECT_FALSE(nodes[1].numerical);
  EXPECT_EQ(nodes[1].sources, std::vector<int>{0});
  // Node 2's answer at step 2 is step 1's (late); node 1 always answers its own step.
  const auto steps = steps_answering({{1, {0, 1, 2, 3, 4}}, {2, {0, 1, 1, 3, 1}}}, 5);
  const PlatformReplay replay = platform_replay(pointers(steps), 5, nodes, 1, 1);
  EXPECT_EQ(actuator_row(replay.schedule, 0), (std::vector<std::int64_t>{0, 1, 1, 3, 1}));
  ASSERT_EQ(replay.schedule.storey_used.size(), 1u);
  EXPECT_TRUE(replay.schedule.storey_used[0].empty());  // always on its own answer
  EXPECT_EQ(replay.late_steps, 2u);
  EXPECT_EQ(replay.oldest, 3);
  EXPECT_DOUBLE_EQ(replay.mean_age, 2.0);
}

TEST(PlatformReplay, AlignedPutsEachAnswerBackAtTheStepItAnswers) {
  // Step 2 used step 1's answer again; step 2's own answer was never used: interpolated.
  EXPECT_EQ(aligned({0, 1, 1, 3}, {10.0, 11.0, 11.0, 13.0}),
            (std::vector<double>{10.0, 11.0, 12.0, 13.0}));
  EXPECT_EQ(aligned({}, {1.0, 2.0}), (std::vector<double>{1.0, 2.0}));
}

}  // namespace
}  // namespace rths::identify
