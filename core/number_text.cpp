#include "core/number_text.h"

#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>

namespace rths::core {

std::optional<double> parse_finite(std::string_view token) {
  if (token.empty() || std::isspace(static_cast<unsigned char>(token.front()))) return std::nullopt;
  const std::string text(token);  // strtod needs a terminated string
  char* end = nullptr;
  const double value = std::strtod(text.c_str(), &end);
  if (end != text.c_str() + text.size() || !std::isfinite(value)) return std::nullopt;
  return value;
}

std::string format_number(double value) { return format_number(value, 6); }

std::string format_number(double value, int significant_digits) {
  char buffer[48];
  std::snprintf(buffer, sizeof buffer, "%.*g", significant_digits, value);
  return buffer;
}

std::string format_percent(double fraction, int significant_digits) {
  return format_number(100.0 * fraction, significant_digits) + " %";
}

std::string printable(std::string_view token) {
  constexpr std::size_t kMax = 40;
  std::string out;
  for (std::size_t i = 0; i < token.size() && i < kMax; ++i) {
    const auto byte = static_cast<unsigned char>(token[i]);
    if (byte >= 0x20 && byte < 0x7f) {
      out += static_cast<char>(byte);
    } else {
      char escaped[8];
      std::snprintf(escaped, sizeof escaped, "\\x%02x", byte);
      out += escaped;
    }
  }
  if (token.size() > kMax) out += "...";
  return out;
}

}  // namespace rths::core
