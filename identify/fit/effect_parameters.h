#pragma once
// What an identified effect measured: its parameters from a fit, each with its value, the fit's
// standard error (the 68 % half-width of its confidence interval, from the Jacobian at the
// optimum; 0 when the fit gives none, e.g. a held parameter) and its SI unit.
//
// Input: the fit of a channel model, the effect (it must be in the model: otherwise the list is
// empty) and the channel's signals (the parameter layout's scales depend on them).

#include <string>
#include <vector>

#include "identify/fit/fit.h"
#include "identify/fit/identify.h"

namespace rths::identify {

struct ParameterEstimate {
  std::string name, unit;
  double value = 0.0, std_error = 0.0;
  // "time_constant = 8.02 ms +/- 0.011 ms": seconds, metres and their rates in milli-units.
  std::string describe() const;
};

std::vector<ParameterEstimate> effect_parameters(const FitResult& fit, Effect effect,
                                                 const SignalScales& scales);

// The signals of `channel` that `id` fitted. Throws std::invalid_argument when it has none.
const ChannelSignals& identified_signals(const Identification& id, Channel channel);

}  // namespace rths::identify
