#pragma once
// The fixed UDP frames a lab's real-time controller exchanges with a host, packed and unpacked
// from a configured layout (config::FrameLayout: fields in order, no gaps; each f64, f32, i32 or
// u32, little or big endian, with a scale). One codec serves both ends: the controller node
// encodes commands and decodes feedback, the controller emulator the other way round.
//
// Values are SI (m, m/s, s, N); on the wire each is SI / scale (scale 0 = 1), integer types
// rounded to the nearest. f64 with scale 1 carries a double's bits unchanged (a lockstep run over
// a controller then equals the in-process run bit for bit); f32 keeps 24 bits of mantissa.
//
//   The layout's own check, its size and each field's: runtime/node/controller_link.h, where
//   every command that reads a study checks a controller block the same way.
//   encode(layout, values, bytes)  -> false when a value does not fit its type (not finite, or
//                                     beyond an integer's range); bytes then unspecified. PADDING
//                                     fields are written 0; DIAGNOSTIC fields take
//                                     values.diagnostics in layout order (0 past its end).
//   decode(layout, bytes, values)  -> kWrongSize (size != frame_size), kNonFinite (a float field
//                                     of any role but PADDING NaN or infinite), or kOk with every
//                                     role's value filled. PADDING fields are never read: their
//                                     bytes are the controller's, whatever they hold.
//   diagnostic_fields(layout)      -> the layout's DIAGNOSTIC fields, in order (their names,
//                                     units and bounds).

#include <cstdint>
#include <string>
#include <vector>

#include "rths/proto/deployment.pb.h"
#include "runtime/node/controller_link.h"

namespace rths::controller_node {

using Direction = runtime::FrameDirection;

// Every role's value, SI; vectors indexed by actuator (sized by the caller or by decode()).
struct FrameValues {
  std::int64_t counter = 0;
  std::int64_t status = 0;
  bool has_status = false;  // decode: the layout has a STATUS field
  double time = 0.0;        // s
  std::vector<double> target_displacement, target_velocity;   // m, m/s
  std::vector<double> measured_displacement, measured_force;  // m, N
  int non_finite_field = -1;  // decode: kNonFinite names the field (index in the layout)
  // decode: the CONTROLLER_EPOCH field's value (has_epoch: the layout has one), and the
  // DIAGNOSTIC fields' SI values in layout order (sized by decode, no allocation once sized).
  std::int64_t epoch = 0;
  bool has_epoch = false;
  std::vector<double> diagnostics;
};

enum class FrameVerdict { kOk, kWrongSize, kNonFinite };
std::string to_string(FrameVerdict verdict);

using runtime::frame_size;

bool encode(const config::FrameLayout& layout, const FrameValues& values,
            std::vector<std::uint8_t>& bytes);

// `actuators` sizes the value vectors (fields beyond it are ignored: runtime::check_frame_layout
// refuses them).
FrameVerdict decode(const config::FrameLayout& layout, const std::uint8_t* data, std::size_t size,
                    int actuators, FrameValues& values);

std::vector<config::FrameField> diagnostic_fields(const config::FrameLayout& layout);

}  // namespace rths::controller_node
