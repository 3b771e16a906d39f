#pragma once
// One DDS domain for the tests that run processes over Cyclone DDS, each test on topics of its
// own (transport/topic_scope.h), in place of a ledger of domain ids.
//
//   kSharedDomain: the domain those tests share.
//   dds_scope_for(name, pid) -> a topic scope for `name` (any text) in process `pid`: its letters
//     and digits with '_' for anything else, cut to 60 characters, then the FNV-1a hash of the
//     whole name (names cut alike stay apart) and the pid (the same test run twice at once, by two
//     people on one machine, stays apart).
//   scope_dds_to_this_test() -> kSharedDomain, having scoped the topics of this process, and of
//     every process it starts from then on, to the running test (its full gtest name) and this
//     process. Call it in the test's own thread before any DDS endpoint of the test exists.
// A test that counts DDS participants or entities on its domain, or whose processes do not
// inherit this process's environment, keeps a domain of its own (docs/development.md).

#include <gtest/gtest.h>
#include <unistd.h>

#include <cctype>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "transport/topic_scope.h"

namespace rths::test {

inline constexpr int kSharedDomain = 10;

inline std::string dds_scope_for(const std::string& name, long pid) {
  std::string scope;
  std::uint32_t hash = 2166136261u;  // FNV-1a, 32 bits
  for (const char c : name) {
    hash = (hash ^ static_cast<unsigned char>(c)) * 16777619u;
    if (scope.size() < 60) scope += std::isalnum(static_cast<unsigned char>(c)) ? c : '_';
  }
  char tail[32];
  std::snprintf(tail, sizeof tail, "_%08x_%ld", static_cast<unsigned>(hash), pid);
  return scope + tail;
}

inline int scope_dds_to_this_test() {
  const testing::TestInfo* info = testing::UnitTest::GetInstance()->current_test_info();
  const std::string name = std::string(info->test_suite_name()) + "." + info->name();
  ::setenv(transport::kTopicScopeVariable, dds_scope_for(name, ::getpid()).c_str(), 1);
  return kSharedDomain;
}

}  // namespace rths::test
