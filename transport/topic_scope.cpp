#include "transport/topic_scope.h"

#include <cstdlib>
#include <stdexcept>

namespace rths::transport {

namespace {

bool topic_name_character(char c) {
  return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_';
}

}  // namespace

std::string topic_prefix_for_scope(const std::string& scope) {
  if (scope.empty()) return "rths";
  const std::string named = std::string(kTopicScopeVariable) + " '" + scope + "'";
  if (scope.size() > kMaxScopeLength)
    throw std::invalid_argument(named + " has " + std::to_string(scope.size()) +
                                " characters; a topic scope has at most " +
                                std::to_string(kMaxScopeLength));
  for (const char c : scope)
    if (!topic_name_character(c))
      throw std::invalid_argument(named + " holds '" + std::string(1, c) +
                                  "'; a topic scope is letters, digits and '_' only");
  return "rths_" + scope;
}

std::string scoped_topic_prefix() {
  const char* scope = std::getenv(kTopicScopeVariable);
  return topic_prefix_for_scope(scope ? scope : "");
}

}  // namespace rths::transport
