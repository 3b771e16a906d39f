#pragma once
// A time as messages print it: milliseconds to three significant digits ("14 ms", "0.586 ms",
// "1.23e+03 ms"). One rule for every summary, warning and diagnosis that states a lag or a wait;
// a block's description that names its own parameters asks for 6 digits ("14.25 ms").

#include <string>

namespace rths::core {

std::string format_ms(double seconds, int significant_digits = 3);

}  // namespace rths::core
