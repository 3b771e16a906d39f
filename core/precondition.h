#pragma once
// The one way a block or a config reader states a precondition: a failed one throws
// std::invalid_argument with a message that names the quantity, its value and the rule.

#include <stdexcept>
#include <string>

namespace rths::core {

[[noreturn]] inline void fail(const std::string& message) { throw std::invalid_argument(message); }

inline void require(bool ok, const std::string& message) {
  if (!ok) fail(message);
}

}  // namespace rths::core
