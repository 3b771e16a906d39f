// A run's DDS topic scope (transport/topic_scope.h): the prefix it gives, the scopes it refuses,
// the variable it reads, and two pairs of endpoints on one domain (the shared one, each test's
// own scope) that hear each other only when their scopes agree. The test suite's scopes
// (tests/support/dds_scope.h) are valid ones and tell tests and processes apart.
#include <gtest/gtest.h>

#include <cstdlib>
#include <stdexcept>

#include "runtime/launch/launch.h"
#include "tests/support/dds_scope.h"
#include "transport/dds_endpoint.h"
#include "transport/topic_scope.h"

namespace rths::transport {
namespace {

using namespace std::chrono_literals;

std::string refusal(const std::string& scope) {
  try {
    topic_prefix_for_scope(scope);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "accepted";
}

TEST(TopicScope, NoScopeKeepsThePlainPrefixAndAScopeExtendsIt) {
  EXPECT_EQ(topic_prefix_for_scope(""), "rths");
  EXPECT_EQ(topic_prefix_for_scope("Suite_Test_1a2b"), "rths_Suite_Test_1a2b");
  EXPECT_EQ(topic_prefix_for_scope(std::string(kMaxScopeLength, 'x')),
            "rths_" + std::string(kMaxScopeLength, 'x'));
}

TEST(TopicScope, ABadScopeIsRefusedNamingTheVariableAndTheProblem) {
  EXPECT_EQ(refusal("run.1"),
            "RTHS_DDS_SCOPE 'run.1' holds '.'; a topic scope is letters, digits and '_' only");
  EXPECT_EQ(refusal("a b"),
            "RTHS_DDS_SCOPE 'a b' holds ' '; a topic scope is letters, digits and '_' only");
  const std::string long_scope(kMaxScopeLength + 1, 'x');
  EXPECT_EQ(refusal(long_scope), "RTHS_DDS_SCOPE '" + long_scope +
                                     "' has 101 characters; a topic scope has at most 100");
}

TEST(TopicScope, TheScopedPrefixIsReadFromTheVariable) {
  ::setenv(kTopicScopeVariable, "from_the_variable", 1);
  EXPECT_EQ(scoped_topic_prefix(), "rths_from_the_variable");
  ::setenv(kTopicScopeVariable, "", 1);
  EXPECT_EQ(scoped_topic_prefix(), "rths");
  ::unsetenv(kTopicScopeVariable);
  EXPECT_EQ(scoped_topic_prefix(), "rths");
  ::setenv(kTopicScopeVariable, "bad-scope", 1);
  EXPECT_THROW(scoped_topic_prefix(), std::invalid_argument);
  ::unsetenv(kTopicScopeVariable);
}

// An endpoint left to the default prefix under a bad scope opens nothing and says why.
TEST(TopicScope, AnEndpointUnderABadScopeIsRefusedNamingIt) {
  runtime::ensure_dds_config();
  ::setenv(kTopicScopeVariable, "bad-scope", 1);
  DdsEndpointOptions options;
  options.domain_id = static_cast<std::uint32_t>(test::kSharedDomain);
  std::string refused;
  try {
    DdsEndpoint endpoint(options);
  } catch (const std::invalid_argument& e) {
    refused = e.what();
  }
  ::unsetenv(kTopicScopeVariable);
  EXPECT_EQ(refused,
            "RTHS_DDS_SCOPE 'bad-scope' holds '-'; a topic scope is letters, digits and '_' only");
}

TEST(TopicScope, TheSuitesScopesAreValidAndDifferByTestAndByProcess) {
  const std::string long_name = "Suite." + std::string(200, 'n') + "/3";
  const std::string scope = test::dds_scope_for(long_name, 4194304);
  EXPECT_NO_THROW(topic_prefix_for_scope(scope));
  EXPECT_LE(scope.size(), kMaxScopeLength);
  EXPECT_EQ(scope, test::dds_scope_for(long_name, 4194304));
  EXPECT_NE(scope, test::dds_scope_for(long_name, 4194305));
  EXPECT_NE(scope, test::dds_scope_for("Suite." + std::string(200, 'n') + "/4", 4194304));
  EXPECT_EQ(test::dds_scope_for("Suite.Test/1", 7).substr(0, 13), "Suite_Test_1_");
}

// A coordinator and a node on one domain: the node, on the default prefix, hears the coordinator
// of this test's scope, and nothing from one of another scope.
TEST(TopicScope, OnOneDomainOnlyEndpointsOfOneScopeHearEachOther) {
  runtime::ensure_dds_config();
  const int domain = test::scope_dds_to_this_test();
  const std::string own = scoped_topic_prefix();
  const auto options = [&](bool coordinator, const std::string& prefix) {
    DdsEndpointOptions o;
    o.domain_id = static_cast<std::uint32_t>(domain);
    o.coordinator = coordinator;
    o.node_id = coordinator ? kCoordinatorId : 1;
    o.topic_prefix = prefix;
    return o;
  };
  DdsEndpoint node(options(false, ""));
  DdsEndpoint stranger(options(true, own + "_other"));
  DdsEndpoint coordinator(options(true, own));
  Message command;
  command.run_id = "scoped";
  command.node_id = 1;
  command.kind = 4;
  command.step = 3;
  stranger.send(command);  // its writer waits for a reader of its topic: none comes
  command.step = 5;
  coordinator.send(command);
  const auto got = node.receive(2s);
  ASSERT_TRUE(got.has_value());
  EXPECT_EQ(got->step, 5);
  EXPECT_FALSE(node.receive(200ms).has_value()) << "the other scope's command reached the node";
  EXPECT_EQ(stranger.matched_writers() + stranger.matched_peers(), 0);
}

}  // namespace
}  // namespace rths::transport
