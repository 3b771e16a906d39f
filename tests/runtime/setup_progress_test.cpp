// A node's set-up progress (runtime/node/setup_progress.h): past its quiet time a line names the
// node, its phase and the time so far; a short set-up prints nothing; a substructure node's
// set-up of a matrix structure names each of its phases.
#include "runtime/node/setup_progress.h"

#include <gtest/gtest.h>

#include <condition_variable>
#include <mutex>
#include <string>
#include <vector>

#include "runtime/node/schema.h"
#include "study/study.h"
#include "substructure_nodes/substructure_service.h"

namespace rths::runtime {
namespace {

// A clock that moves `step_s` seconds each time it is read (the constructor reads it once).
std::function<double()> ticking_clock(double step_s) {
  return [now = 0.0, step_s]() mutable { return now += step_s; };
}

// Lines as printed, from any thread.
struct Lines {
  std::mutex mutex;
  std::condition_variable added;
  std::vector<std::string> lines;
  SetupProgress::Print print() {
    return [this](const std::string& line) {
      std::lock_guard guard(mutex);
      lines.push_back(line);
      added.notify_all();
    };
  }
  bool has(const std::string& text) {
    std::lock_guard guard(mutex);
    for (const std::string& line : lines)
      if (line.find(text) != std::string::npos) return true;
    return false;
  }
};

TEST(SetupProgress, PastItsQuietTimeEachPhaseEndNamesThePhaseAndTheTimeSoFar) {
  Lines out;
  {
    SetupProgress progress("node 1 (substructure)",
                           {.quiet = 3.0, .every = 5.0, .clock_s = ticking_clock(2.0)},
                           out.print());
    progress.phase("reading the structure");  // 2 s: quiet
    progress.phase("building the case");      // 4 s: a line on the phase that ends
    progress.phase("building the part");      // 6 s: within 5 s of the last line
    progress.finish();                        // 8 s, within 5 s again; then 10 s
  }
  ASSERT_EQ(out.lines.size(), 2u);
  EXPECT_EQ(out.lines[0],
            "node 1 (substructure): setting up its part: reading the structure; 4.0 s so far");
  EXPECT_EQ(out.lines[1], "node 1 (substructure): part set up in 10.0 s");
}

TEST(SetupProgress, ASetUpShorterThanItsQuietTimePrintsNothing) {
  Lines out;
  SetupProgress progress("node 1 (substructure)",
                         {.quiet = 3.0, .every = 5.0, .clock_s = ticking_clock(0.5)}, out.print());
  progress.phase("reading the structure");
  progress.phase("building the case");
  progress.finish();
  EXPECT_TRUE(out.lines.empty());
}

// A phase that lasts: the watcher's own looks print while nothing else calls in.
TEST(SetupProgress, TheWatcherPrintsWhileOnePhaseLasts) {
  Lines out;
  SetupProgress progress("node 1 (substructure)",
                         {.quiet = 1.0, .every = 0.0, .clock_s = ticking_clock(1.0)}, out.print());
  progress.phase("reading the structure");
  progress.watch(0.001);
  std::unique_lock lock(out.mutex);
  EXPECT_TRUE(out.added.wait_for(lock, std::chrono::seconds(30), [&] {
    return out.lines.size() >= 2;
  })) << "the watcher printed no line in 30 s";
  EXPECT_NE(out.lines.back().find("setting up its part: reading the structure; "),
            std::string::npos)
      << out.lines.back();
}

// A substructure node (the real service, no transport) assigned the 20-DOF frame given by
// matrices: each phase of its set-up is named, then its end.
TEST(SetupProgress, ASubstructureNodeNamesEachPhaseOfItsSetUp) {
  const std::string matrices = std::string(RTHS_SOURCE_DIR) + "/configs/matrices/";
  Assign assign;
  assign.set_schema_version(kSchemaVersion);
  *assign.mutable_study() = study::parse_study(
      "name: \"frame20\" structure { matrices { mass { file: \"" + matrices +
          "frame20_mass.mtx\" } stiffness { file: \"" + matrices +
          "frame20_stiffness.mtx\" } } damping { modal_zeta: 0.05 } } "
          "motion { path: \"none.at2\" } integrator { kind: EXPLICIT_NEWMARK dt: 0.002 } "
          "substructuring { experimental_dofs { dof: 1 mass: 20 stiffness: 2.0e6 zeta: 0.02 } } "
          "cases { name: \"reference\" }",
      "test");
  assign.set_case_name("reference");
  assign.mutable_node()->set_id(1);
  assign.mutable_node()->set_kind(config::NodeSpec::SUBSTRUCTURE);
  assign.set_dt(0.002);
  for (int s = 0; s < 20; ++s) assign.add_storeys(s);
  substructure_nodes::SubstructureService node(1, "");
  Lines out;
  node.set_setup_progress({.quiet = 0.0, .every = 0.0, .clock_s = ticking_clock(1.0)}, out.print());
  const std::vector<transport::Message> replies = node.handle(pack("run-1", 1, ASSIGN, 0, assign));
  ASSERT_EQ(replies.size(), 1u);
  Ready ready;
  ASSERT_TRUE(unpack(replies[0], ready));
  EXPECT_EQ(ready.error(), "");
  for (const std::string phase :
       {"node 1 (substructure): setting up its part: reading and checking the study's structure; ",
        "setting up its part: building case 'reference' on the 20-DOF structure; ",
        "setting up its part: building its numerical part (20 storeys); ",
        "setting up its part: building its delay stages; ",
        "node 1 (substructure): part set up in "})
    EXPECT_TRUE(out.has(phase)) << "no line has: " << phase;
}

}  // namespace
}  // namespace rths::runtime
