#include "core/compensator.h"

#include <stdexcept>

namespace rths::core {

Linearity Compensator::linearity() const {
  return {Linearity::Kind::kNone,
          "compensator " + describe() + " does not state its linear dynamics"};
}

std::complex<double> Compensator::frequency_response(double) const {
  throw std::invalid_argument(linearity().note);
}

LinearBlock Compensator::state_space() const { throw std::invalid_argument(linearity().note); }

}  // namespace rths::core
