#pragma once
// A time as messages print it: milliseconds to three significant digits ("14 ms", "0.586 ms",
// "1.23e+03 ms"). One rule for every summary, warning and diagnosis that states a lag or a wait.

#include <string>

namespace rths::core {

std::string format_ms(double seconds);

}  // namespace rths::core
