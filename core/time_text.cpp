#include "core/time_text.h"

#include <iomanip>
#include <sstream>

namespace rths::core {

std::string format_ms(double seconds) {
  std::ostringstream out;
  out << std::setprecision(3) << seconds * 1e3 << " ms";
  return out.str();
}

}  // namespace rths::core
