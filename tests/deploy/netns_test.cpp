// Network-namespace topology: built, reachable across the veth links, removed afterwards.
// Skipped (with the reason) where this process may not create namespaces.
#include "deploy/netns.h"

#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>

#include "util/process.h"

namespace rths::deploy {

using util::run_command;
namespace {

bool contains(const std::vector<std::string>& names, const std::string& name) {
  return std::find(names.begin(), names.end(), name) != names.end();
}

// The namespaces this process made: other suites' processes make and remove theirs meanwhile
// (namespace_support() itself probes with one), so the host's whole list is no witness.
std::vector<std::string> own_namespaces() {
  const std::string own_prefix = "rths-" + std::to_string(::getpid()) + "-";
  std::vector<std::string> own;
  for (const auto& name : list_namespaces()) {
    if (name.rfind(own_prefix, 0) == 0) own.push_back(name);
  }
  return own;
}

class NetnsTest : public ::testing::Test {
 protected:
  void SetUp() override {
    if (const auto reason = namespace_support()) GTEST_SKIP() << *reason;
  }
};

TEST_F(NetnsTest, TwoSitesPingEachOtherAndVanishAfterTeardown) {
  std::vector<std::string> made;
  {
    NamespaceTopology topology({{"alpha", "beta"}, "10.231.1"});
    made = topology.namespaces();
    ASSERT_EQ(made.size(), 3u);  // two sites + hub
    const auto host = list_namespaces();
    for (const auto& name : made) EXPECT_TRUE(contains(host, name)) << name;
    EXPECT_EQ(topology.site("alpha").address, "10.231.1.1");
    EXPECT_EQ(topology.site("beta").address, "10.231.1.2");

    auto argv = topology.exec_prefix("alpha");
    for (const char* arg : {"ping", "-c", "3", "-i", "0.2", "-W", "2", "10.231.1.2"}) {
      argv.push_back(arg);
    }
    const auto ping = util::run_command(argv, std::chrono::seconds(10));
    EXPECT_EQ(ping.exit_code, 0) << ping.output;
    EXPECT_NE(ping.output.find("3 received"), std::string::npos) << ping.output;

    // The site is isolated from the host: the host's loopback services are not its loopback,
    // and an address outside the topology is unreachable.
    auto outside = topology.exec_prefix("beta");
    for (const char* arg : {"ping", "-c", "1", "-W", "1", "10.231.2.1"}) outside.push_back(arg);
    EXPECT_NE(util::run_command(outside, std::chrono::seconds(5)).exit_code, 0);
  }
  const auto after = list_namespaces();
  for (const auto& name : made) EXPECT_FALSE(contains(after, name)) << name << " left behind";
}

TEST_F(NetnsTest, FailedBuildRemovesWhatItMade) {
  const auto before = own_namespaces();
  // The second site's address collides with nothing, but an invalid subnet octet is caught
  // before anything is made; an invalid name likewise.
  EXPECT_THROW(NamespaceTopology({{"ok", "Bad-Name"}, "10.231.1"}), std::invalid_argument);
  EXPECT_THROW(NamespaceTopology({{"ok"}, "10.231.300"}), std::invalid_argument);
  EXPECT_EQ(own_namespaces(), before);
}

TEST_F(NetnsTest, TopologiesSideBySideAreIsolated) {
  NamespaceTopology first({{"a", "b"}, "10.231.3"});
  NamespaceTopology second({{"a", "b"}, "10.231.3"});
  EXPECT_NE(first.site("a").netns, second.site("a").netns);
  // Same addresses, different hubs: each pair reaches its own peer.
  for (const auto* topology : {&first, &second}) {
    auto argv = topology->exec_prefix("a");
    for (const char* arg : {"ping", "-c", "1", "-W", "2", "10.231.3.2"}) argv.push_back(arg);
    EXPECT_EQ(util::run_command(argv, std::chrono::seconds(5)).exit_code, 0);
  }
}

TEST(NetnsList, ReadsNamesAndIdsAndSkipsTheErrorsOfANamespaceDeletedMeanwhile) {
  const std::string output =
      "rths-17726-f9b7a2-a (id: 3)\n"
      "Error: Peer netns reference is invalid.\n"
      "rths-17726-f9b7a2-hub\n"
      "Error: Peer netns reference is invalid.\n"
      "lab_site.2 (id: 12)\n";
  EXPECT_EQ(
      parse_namespace_list(output),
      (std::vector<std::string>{"rths-17726-f9b7a2-a", "rths-17726-f9b7a2-hub", "lab_site.2"}));
  EXPECT_TRUE(parse_namespace_list("").empty());
}

TEST(NetnsSpec, RejectsBadSpecsNamingTheProblem) {
  try {
    NamespaceTopology topology({{"x", "x"}, "10.231.0"});
    FAIL() << "duplicate site accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("'x' appears twice"), std::string::npos) << e.what();
  }
  EXPECT_THROW(NamespaceTopology({{}, "10.231.0"}), std::invalid_argument);
  EXPECT_THROW(NamespaceTopology({{"hub"}, "10.231.0"}), std::invalid_argument);
}

// A subnet the sites cannot be given is refused, named, before anything is made.
TEST(NetnsSpec, RejectsALoopbackThisNetworkOrMulticastSubnet) {
  for (const char* subnet : {"127.0.0", "0.1.2", "224.0.0", "255.255.255"}) {
    try {
      validate_topology({{"a"}, subnet});
      ADD_FAILURE() << subnet << " accepted";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("is not a unicast network for the sites"),
                std::string::npos)
          << e.what();
    }
  }
  for (const char* subnet : {"10.231.0", "192.168.7", "172.16.0", "1.2.3", "223.255.255"})
    EXPECT_NO_THROW(validate_topology({{"a"}, subnet})) << subnet;
}

}  // namespace
}  // namespace rths::deploy
