#pragma once
// Unknown enum values in a config. Protobuf keeps a number its enum does not name (proto3 enums
// are open), and code that switches over the known values then falls to a default: an
// `integrator { kind: 77 }` ran as explicit Newmark. This check refuses any such value, naming it.
//
// require_known_enums(message, source): walks every set field of `message`, nested messages and
// repeated fields included; at the first enum field whose value (or element) the enum does not
// name, throws std::invalid_argument "SOURCE: FIELD.PATH: N is not a known value (NAME, NAME, ...)"
// (repeated elements as FIELD[i]). Loading only; allocates.

#include <string>

namespace google::protobuf {
class Message;
}

namespace rths::study {

void require_known_enums(const google::protobuf::Message& message, const std::string& source);

}  // namespace rths::study
