#pragma once
// Internal to the sweep's files (sweep_grid, sweep_csv, sweep_report): how they write and read
// numbers, so a number written by one reads back the same in another.

#include <fmt/format.h>

#include <charconv>
#include <cstddef>
#include <stdexcept>
#include <string>

namespace rths::analysis::sweep_internal {

// 17 significant digits: a double written and read back is the same double.
inline std::string format_number(double x) { return fmt::format("{:.17g}", x); }

// A whole number (index or count) from `text`; throws std::invalid_argument naming `where`.
inline std::size_t parse_index(const std::string& text, const std::string& where) {
  std::size_t value = 0;
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (error != std::errc() || end != text.data() + text.size()) {
    throw std::invalid_argument(where + ": '" + text + "' is not a whole number");
  }
  return value;
}

}  // namespace rths::analysis::sweep_internal
