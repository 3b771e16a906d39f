#pragma once
// Designing a delay compensator from an identified actuator (the `measured` channel model of
// identify.h): the fitted delay, gain, first-order time constant and second-order natural
// frequency / damping become core::PlantModel and config stages, and a compensator of the asked
// kind is written as a study-config case (`rths identify DATA --design-compensator KIND --out
// DIR`).
//
// Designs (core/compensation.h has the blocks' equations):
//   polynomial    order 2, lead L = delay + T + 2 zeta / wn (the plant's low-frequency lag),
//                 spacing = L / 2 rounded to whole steps (keeps the Lagrange weights O(1)).
//   ats           initial a0 = 1 / gain, a1 = L, a2 = delay T + delay^2 / 2 (the first-order-plus-
//                 delay inverse), bounds a0 [0.5/gain, 2/gain], a1 [0, 3 L], a2 [-3|a2|-1e-6, 3|a2|+1e-6],
//                 window 1 s, no derivative filter (simulation data are noise free; set it for a lab).
//   model-based   the plant's inverse with lead order 2 and roll-off min(50 Hz, fs / 8).
//   model-based-adaptive  the same inverse with an adaptive correction in front (window 1 s,
//                 a0 [0.5, 2], a1 [-L, L], a2 [-L^2, L^2]: the model may be off by up to its own
//                 lag L), for when the actuator in the test may differ from the identified one.
// The identified lab-scale effects (offset/drift, backlash, velocity saturation) are not inverted;
// they are listed in `ignored`, as identify/lab/predict.h does. A negative fitted delay (a lead) is
// used as zero and listed.
// Errors (std::invalid_argument): no actuator model, or one with nothing to compensate (no
// delay and no dynamics); never a silent fall-back to no compensation.

#include <filesystem>
#include <string>
#include <vector>

#include "core/compensation.h"
#include "identify/model/model.h"
#include "rths/proto/config.pb.h"

namespace rths::identify {

enum class CompensatorKind { kPolynomial, kAdaptiveTimeSeries, kModelBased, kAdaptedModelBased };
// "polynomial" | "ats" | "model-based" | "model-based-adaptive". Throws std::invalid_argument
// listing them.
CompensatorKind parse_compensator_kind(const std::string& name);
std::string compensator_kind_name(CompensatorKind kind);

struct CompensatorDesign {
  core::PlantModel plant;   // what the identification found
  double plant_lag = 0.0;   // s, its low-frequency lag L
  config::Case study_case;  // the identified actuator's stages + the compensation
  std::vector<std::string> ignored;
  std::string summary;  // one paragraph for the terminal
};

// @pre actuator.channel == Channel::kMeasured (else throws). dt is the step of the planned test
// (s).
CompensatorDesign design_compensator(const ChannelModel& actuator, const SignalScales& scales,
                                     CompensatorKind kind, double dt);

// Writes DIR/compensator_<kind>.textproto: a `cases { ... }` block to append to a study config.
// Returns the path. Throws std::runtime_error naming the file when it cannot be written.
std::filesystem::path write_compensator_case(const CompensatorDesign& design,
                                             const std::filesystem::path& directory);

}  // namespace rths::identify
