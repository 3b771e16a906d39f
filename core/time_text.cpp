#include "core/time_text.h"

#include "core/number_text.h"

namespace rths::core {

std::string format_ms(double seconds, int significant_digits) {
  return format_number(seconds * 1e3, significant_digits) + " ms";
}

}  // namespace rths::core
