// The node programs (runtime/node/node_main.h) check the study given with --config as `rths run`
// checks it: a bad study is refused at start, exit 2, with the message `run` gives, never after
// waiting for a coordinator that would never assign it (exit 1, "no coordinator assigned").
#include "runtime/node/node_main.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <utility>
#include <vector>

#include "tests/runtime/test_support.h"
#include "tests/support/dds_scope.h"
#include "util/process.h"

namespace rths::runtime {
namespace {

const std::string kMotion =
    std::string(RTHS_DATA_DIR) + "/ground_motions/RSN175_IMPVALL.H_H-E12140.AT2";

// A sound study on DDS domain `domain` with `swap` = {what, by} replaced (the first occurrence).
std::string study_with(const std::pair<std::string, std::string>& swap, int domain) {
  std::string text =
      "name: \"node_check\"\n"
      "structure { sdof { period: 0.5 mass: 1000 } damping { modal_zeta: 0.05 } }\n"
      "motion { path: \"" +
      kMotion +
      "\" duration: 1 }\n"
      "integrator { kind: EXPLICIT_NEWMARK dt: 0.001 }\n"
      "substructuring { experimental_fraction: 0.3333 model { linear {} } }\n"
      "cases { name: \"reference\" }\n"
      "deployment { domain_id: " +
      std::to_string(domain) +
      " nodes { id: 1 kind: SUBSTRUCTURE }\n"
      "             nodes { id: 2 kind: ACTUATOR_EMULATOR } }\n";
  const auto at = swap.first.empty() ? std::string::npos : text.find(swap.first);
  if (at != std::string::npos) text.replace(at, swap.first.size(), swap.second);
  return text;
}

// What `rths run` says of the study: its message after "rths: " (the line's rest).
std::string run_refusal(const std::filesystem::path& study, const std::filesystem::path& out) {
  const util::CommandResult run =
      util::run_command({std::string(RTHS_BINARY_DIR) + "/cli/rths", "run", study.string(),
                         "--no-plots", "--out", out.string()});
  EXPECT_EQ(run.exit_code, 2) << run.output;
  const auto at = run.output.find("rths: ");
  if (at == std::string::npos) return "(no message from rths run: " + run.output + ")";
  const auto end = run.output.find('\n', at);
  return run.output.substr(at + 6, end == std::string::npos ? end : end - at - 6);
}

TEST(NodeMain, EveryNodeProgramRefusesABadStudyAtStartWithTheMessageRunGives) {
  const int domain = test::scope_dds_to_this_test();
  const auto dir =
      std::filesystem::temp_directory_path() / ("rths_node_main_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::vector<std::pair<std::string, std::string>> bad{
      {"path: \"" + kMotion + "\"", "path: \"/nonexistent/motion.AT2\""},
      {"duration: 1 }", "duration: 1 sha256: \"00\" }"},
      {"dt: 0.001 }", "dt: 0.001 }\nservo { rate: 1500 }"},
      {"cases { name: \"reference\" }",
       "cases { name: \"reference\" delay { trace { path: \"/nonexistent/lag.txt\" } } }"},
      {"nodes { id: 2 kind: ACTUATOR_EMULATOR }", "nodes { id: 1 kind: ACTUATOR_EMULATOR }"},
      {"nodes { id: 2 kind: ACTUATOR_EMULATOR }", "nodes { id: 2 kind: CONTROLLER }"},
      {"period: 0.5", "period: -0.5"},
      {"modal_zeta: 0.05", "modal_zeta: nan"},
      {"experimental_fraction: 0.3333", "experimental_fraction: 3"},
      {"name: \"node_check\"", "name: \"node_check\" bogus_field: 1"},
  };
  const std::vector<std::pair<std::string, std::string>> programs{
      {"rths-substructure-node", "substructure_nodes"},
      {"rths-actuator-emulator", "actuator_emulator"},
      {"rths-controller-node", "controller_node"}};
  // The sound study passes the check: the node then waits for its coordinator (none: exit 1).
  const auto sound = dir / "sound.textproto";
  std::ofstream(sound) << study_with({"", ""}, domain);
  const util::CommandResult waits =
      util::run_command({test::program("rths-substructure-node", "substructure_nodes").string(),
                         "--node-id", "1", "--config", sound.string(), "--run-id", "node_check",
                         "--insecure", "--assign-timeout", "0.5"});
  EXPECT_EQ(waits.exit_code, 1) << waits.output;
  for (std::size_t i = 0; i < bad.size(); ++i) {
    SCOPED_TRACE(bad[i].second);
    const auto study = dir / ("bad_" + std::to_string(i) + ".textproto");
    std::ofstream(study) << study_with(bad[i], domain);
    const std::string refusal = run_refusal(study, dir / ("out_" + std::to_string(i)));
    for (const auto& [name, subdir] : programs) {
      const util::CommandResult node = util::run_command(
          {test::program(name, subdir).string(), "--node-id", "1", "--config", study.string(),
           "--run-id", "node_check", "--insecure", "--assign-timeout", "3"});
      EXPECT_EQ(node.exit_code, 2) << name << ": " << node.output;
      EXPECT_NE(node.output.find(name + ": " + refusal), std::string::npos)
          << name << " does not say what `rths run` says (" << refusal << "): " << node.output;
    }
  }
  std::filesystem::remove_all(dir);
}

// A wait that is no time (NaN passed every comparison: the node gave up at once) is refused.
TEST(NodeMain, AnAssignTimeoutThatIsNoTimeIsRefused) {
  for (const char* timeout : {"nan", "-1", "0", "inf"}) {
    const util::CommandResult node = util::run_command(
        {test::program("rths-actuator-emulator", "actuator_emulator").string(), "--node-id", "2",
         "--domain", std::to_string(test::scope_dds_to_this_test()), "--run-id", "node_check",
         "--insecure", "--assign-timeout", timeout});
    EXPECT_EQ(node.exit_code, 2) << timeout << ": " << node.output;
    EXPECT_NE(node.output.find("s is not a time (finite, > 0)"), std::string::npos)
        << timeout << ": " << node.output;
  }
}

}  // namespace
}  // namespace rths::runtime
