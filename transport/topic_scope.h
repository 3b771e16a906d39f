#pragma once
// A run's DDS topic scope: runs on one DDS domain whose topics carry different scopes never match a
// reader to a writer, so they cannot hear each other (DDS matches by topic name). A test suite
// gives each test a scope of its own and shares one domain, instead of a ledger of domain ids.
//
// Input:  the process's environment variable RTHS_DDS_SCOPE (kTopicScopeVariable). A launcher's
//         children inherit it (util::ChildProcess), so a coordinator and its nodes agree; a node
//         started elsewhere must be given the same value.
// Output: the topic prefix of every DdsEndpoint the process opens with an empty one (the
//         default): "rths" when the variable is unset or empty, else "rths_<scope>"; topics are
//         then <prefix>_node<id>_down and <prefix>_node<id>_up (transport/dds_endpoint.h). The
//         DDS Security permissions (`rths pki init`) grant "*_node<id>_...", so any scope is
//         covered.
// A scope is 1 to kMaxScopeLength letters, digits and '_': the alphabet of a DDS topic name,
// whose whole length RTPS bounds at 256 characters.

#include <cstddef>
#include <string>

namespace rths::transport {

inline constexpr const char* kTopicScopeVariable = "RTHS_DDS_SCOPE";
inline constexpr std::size_t kMaxScopeLength = 100;

// "rths" for an empty scope, else "rths_<scope>". Throws std::invalid_argument naming the
// variable, the scope and its first character outside [A-Za-z0-9_], or its length when longer
// than kMaxScopeLength.
std::string topic_prefix_for_scope(const std::string& scope);

// topic_prefix_for_scope of RTHS_DDS_SCOPE (empty when unset); throws as it does.
std::string scoped_topic_prefix();

}  // namespace rths::transport
