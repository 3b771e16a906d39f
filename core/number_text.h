#pragma once
// Numbers in text, as rths reads and prints them in every message and file: one parse rule, one
// print rule, and a safe echo of a bad token. Pure functions of their arguments.

#include <optional>
#include <string>
#include <string_view>

namespace rths::core {

// The number rule: the whole token is one number in C strtod syntax ("1e-3", "-.5", "12") and
// finite; nullopt otherwise ("1.2.3", "nan", "inf", "", "3 m").
std::optional<double> parse_finite(std::string_view token);

// A number as messages print it: %g (6 significant digits, no trailing zeros: "0.014", "1e-05").
std::string format_number(double value);
// The same to `significant_digits` digits (%.*g): 3 gives "14.2", "0.586", "1.23e+03"; 17 gives
// the text that reads back as the same double.
std::string format_number(double value, int significant_digits);

// A fraction as a percentage, as messages print it: 100 x fraction to `significant_digits`
// digits, then " %" (0.01234 gives "1.23 %").
std::string format_percent(double fraction, int significant_digits = 3);

// A token as an error message may show it: bytes outside printable ASCII as \xNN, at most 40
// characters ("..." after), so a binary file never reaches the terminal raw.
std::string printable(std::string_view token);

}  // namespace rths::core
