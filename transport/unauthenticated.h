#pragma once
// What a receiver with a run secret dropped unread because a message's MAC did not verify
// (transport/message_mac.h): how many, and the newest one named, so a run can say who tried.

#include <cstdint>
#include <string>

namespace rths::transport {

struct Unauthenticated {
  std::uint64_t count = 0;
  std::string last;  // the newest: "kind K as node N on node T's topic, writer W"; "" when none
};

}  // namespace rths::transport
