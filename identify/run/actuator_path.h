#pragma once
// One actuator's path as identified from a run's record: what the case declared, what the fit
// found (gain, delay, the effects beyond the declared model), and the identification itself.

#include <string>
#include <vector>

#include "identify/fit/identify.h"

namespace rths::identify {

struct ActuatorPath {
  int actuator = 0;                   // 1-based
  std::vector<std::string> declared;  // the case's stages, as effects
  double declared_gain = 1.0, fitted_gain = 1.0;
  double declared_delay = 0.0, fitted_delay = 0.0;  // s; both 0 when no delay was declared
  Identification id;                                // channels measured and force
  std::vector<std::string> undeclared;              // effects named beyond the declared model
};

}  // namespace rths::identify
