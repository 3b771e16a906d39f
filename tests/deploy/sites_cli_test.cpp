// `rths sites` as a user sees it: exit codes and messages (2 bad config, 3 no namespaces).
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>

#include "deploy/process.h"

namespace rths::deploy {
namespace {

const std::string kRths = std::string(RTHS_BINARY_DIR) + "/cli/rths";
const std::string kConfig = std::string(RTHS_SOURCE_DIR) + "/configs/sites_paper_frame.textproto";

TEST(SitesCli, CheckAcceptsTheShippedConfig) {
  const auto result = run_command({kRths, "sites", kConfig, "--check"});
  EXPECT_EQ(result.exit_code, 0) << result.output;
  EXPECT_NE(result.output.find("3 processes on 3 sites"), std::string::npos) << result.output;
}

TEST(SitesCli, BadConfigExitsTwoNamingTheFile) {
  const auto missing = run_command({kRths, "sites", "/nonexistent/sites.textproto"});
  EXPECT_EQ(missing.exit_code, 2) << missing.output;
  EXPECT_NE(missing.output.find("/nonexistent/sites.textproto"), std::string::npos);
}

// Without the right to make namespaces (here: the same command as user nobody, which needs root
// to arrange), the command says so and exits 3 before touching anything.
TEST(SitesCli, NoNamespacePermissionExitsThreeSayingWhy) {
  if (::geteuid() != 0 || !tool_available("setpriv")) {
    GTEST_SKIP() << "needs root and setpriv to run the command as an unprivileged user";
  }
  const auto copy = std::filesystem::temp_directory_path() / "rths_sites_cli_test";
  std::filesystem::create_directories(copy);
  std::filesystem::permissions(copy, std::filesystem::perms::all);
  const auto result = run_command({"setpriv", "--reuid=65534", "--regid=65534", "--clear-groups",
                                   kRths, "sites", kConfig, "--out", copy.string()});
  EXPECT_EQ(result.exit_code, 3) << result.output;
  EXPECT_NE(result.output.find("network namespaces are not permitted"), std::string::npos)
      << result.output;
  std::filesystem::remove_all(copy);
}

}  // namespace
}  // namespace rths::deploy
