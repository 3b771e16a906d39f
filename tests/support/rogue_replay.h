#pragma once
// The rogue's replay attack (rths_rogue --mode replay): a stranger without the run secret records
// the run's genuine messages off the wire and re-publishes each one byte for byte (run id, stamps,
// payload and MAC as they came) from its own writer on the topic it came from: node 1's and node
// 2's announcements, answers and heartbeats (<prefix>_node<N>_up) and the coordinator's
// assignments and commands to them (<prefix>_node<N>_down), the prefix the process's topic scope
// gives (transport/topic_scope.h: "rths" unscoped). Written against libddsc and the envelope type
// directly, since rths's own endpoint would sign anew.
//
// Inputs: the DDS domain, how long (s), and a flag that ends it early (SIGTERM's).
// Output: how many messages it replayed, by "<topic> kind <K>" (rths.runtime.MessageKind).
// Throws std::runtime_error naming the DDS call that failed.

#include <csignal>
#include <map>
#include <string>

namespace rths::rogue {

std::map<std::string, long> replay(int domain, double seconds,
                                   const volatile std::sig_atomic_t& stop);

}  // namespace rths::rogue
