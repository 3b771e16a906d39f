#include "controller_node/frame.h"

#include <cmath>
#include <cstring>
#include <stdexcept>

namespace rths::controller_node {
namespace {

using Field = config::FrameField;

double scale_of(const Field& f) { return f.scale() == 0.0 ? 1.0 : f.scale(); }

// Writes `n` bytes of `raw` (host order) in the field's byte order.
void put(std::uint8_t* out, const std::uint8_t* raw, std::size_t n, Field::ByteOrder order) {
  const bool swap = (order == Field::ORDER_BIG) == (__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__);
  for (std::size_t i = 0; i < n; ++i) out[i] = raw[swap ? n - 1 - i : i];
}

// The SI value of role `role` (actuator a) in `values`; nullptr for roles without one.
template <class Values>
auto slot(Values& values, Field::Role role, int a) -> decltype(&values.time) {
  switch (role) {
    case Field::TARGET_DISPLACEMENT: return &values.target_displacement.at(a);
    case Field::TARGET_VELOCITY: return &values.target_velocity.at(a);
    case Field::MEASURED_DISPLACEMENT: return &values.measured_displacement.at(a);
    case Field::MEASURED_FORCE: return &values.measured_force.at(a);
    case Field::COMMAND_TIME: return &values.time;
    default: return nullptr;
  }
}

// One field's value as a double in frame units (what encode writes).
double frame_value(const Field& f, const FrameValues& values) {
  switch (f.role()) {
    case Field::COUNTER: return static_cast<double>(values.counter);
    case Field::STATUS: return static_cast<double>(values.status);
    case Field::CONTROLLER_EPOCH: return static_cast<double>(values.epoch);
    case Field::PADDING: return 0.0;
    default: {
      const double* v = slot(values, f.role(), f.actuator());
      return v ? *v / scale_of(f) : 0.0;
    }
  }
}

bool write_field(const Field& f, double value, std::uint8_t* out) {
  if (!std::isfinite(value)) return false;
  std::uint8_t raw[8];
  switch (f.type()) {
    case Field::F32: {
      const float x = static_cast<float>(value);
      if (!std::isfinite(x)) return false;
      std::memcpy(raw, &x, 4);
      break;
    }
    case Field::I32: {
      const double r = std::nearbyint(value);
      if (r < -2147483648.0 || r > 2147483647.0) return false;
      const std::int32_t x = static_cast<std::int32_t>(r);
      std::memcpy(raw, &x, 4);
      break;
    }
    case Field::U32: {
      const double r = std::nearbyint(value);
      if (r < 0.0 || r > 4294967295.0) return false;
      const std::uint32_t x = static_cast<std::uint32_t>(r);
      std::memcpy(raw, &x, 4);
      break;
    }
    default: std::memcpy(raw, &value, 8);
  }
  put(out, raw, runtime::frame_field_size(f.type()), f.byte_order());
  return true;
}

double read_field(const Field& f, const std::uint8_t* in) {
  std::uint8_t raw[8];
  put(raw, in, runtime::frame_field_size(f.type()), f.byte_order());  // the swap is its own inverse
  switch (f.type()) {
    case Field::F32: {
      float x;
      std::memcpy(&x, raw, 4);
      return x;
    }
    case Field::I32: {
      std::int32_t x;
      std::memcpy(&x, raw, 4);
      return x;
    }
    case Field::U32: {
      std::uint32_t x;
      std::memcpy(&x, raw, 4);
      return x;
    }
    default: {
      double x;
      std::memcpy(&x, raw, 8);
      return x;
    }
  }
}

}  // namespace

std::string to_string(FrameVerdict verdict) {
  switch (verdict) {
    case FrameVerdict::kOk: return "ok";
    case FrameVerdict::kWrongSize: return "wrong size";
    default: return "not finite";
  }
}

bool encode(const config::FrameLayout& layout, const FrameValues& values,
            std::vector<std::uint8_t>& bytes) {
  bytes.assign(frame_size(layout), 0);
  std::size_t at = 0, diagnostic = 0;
  for (const Field& f : layout.fields()) {
    double value = frame_value(f, values);
    if (f.role() == Field::DIAGNOSTIC)  // in layout order; a channel not given is written 0
      value = diagnostic < values.diagnostics.size() ? values.diagnostics[diagnostic] / scale_of(f)
                                                     : 0.0;
    diagnostic += f.role() == Field::DIAGNOSTIC ? 1 : 0;
    if (!write_field(f, value, bytes.data() + at)) return false;
    at += runtime::frame_field_size(f.type());
  }
  return true;
}

FrameVerdict decode(const config::FrameLayout& layout, const std::uint8_t* data, std::size_t size,
                    int actuators, FrameValues& values) {
  if (size != frame_size(layout)) return FrameVerdict::kWrongSize;
  const auto n = static_cast<std::size_t>(actuators);
  for (auto* v : {&values.target_displacement, &values.target_velocity,
                  &values.measured_displacement, &values.measured_force})
    v->assign(n, 0.0);
  values.has_status = false;
  values.has_epoch = false;
  values.non_finite_field = -1;
  std::size_t diagnostic = 0;
  std::size_t at = 0;
  int index = -1;
  for (const Field& f : layout.fields()) {
    ++index;
    const std::uint8_t* in = data + at;
    at += runtime::frame_field_size(f.type());
    // A PADDING field's bytes are the controller's spare words, never a value: whatever they
    // hold (an F64 spare left NaN by its model included) must not refuse the frame.
    if (f.role() == Field::PADDING) continue;
    const double x = read_field(f, in);
    if (!std::isfinite(x)) {
      values.non_finite_field = index;
      return FrameVerdict::kNonFinite;
    }
    if (f.role() == Field::COUNTER) {
      values.counter = static_cast<std::int64_t>(x);
    } else if (f.role() == Field::STATUS) {
      values.status = static_cast<std::int64_t>(x);
      values.has_status = true;
    } else if (f.role() == Field::CONTROLLER_EPOCH) {
      values.epoch = static_cast<std::int64_t>(std::llround(x));
      values.has_epoch = true;
    } else if (f.role() == Field::DIAGNOSTIC) {
      if (diagnostic == values.diagnostics.size()) values.diagnostics.push_back(0.0);
      values.diagnostics[diagnostic++] = x * scale_of(f);
    } else {
      if (runtime::per_actuator_role(f.role()) && (f.actuator() < 0 || f.actuator() >= actuators))
        continue;
      if (double* v = slot(values, f.role(), f.actuator())) *v = x * scale_of(f);
    }
  }
  values.diagnostics.resize(diagnostic);
  return FrameVerdict::kOk;
}

std::vector<config::FrameField> diagnostic_fields(const config::FrameLayout& layout) {
  std::vector<config::FrameField> out;
  for (const Field& f : layout.fields())
    if (f.role() == Field::DIAGNOSTIC) out.push_back(f);
  return out;
}

}  // namespace rths::controller_node
