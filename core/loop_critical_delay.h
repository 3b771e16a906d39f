#pragma once
// The pre-run critical-delay check of a structure whose links' specimens carry a dashpot or a
// mass besides their stiffness (a damper between floors): core::check_modal_critical_delay
// (core/stability.h) on the whole structure, its continuous limit from the coupled delayed loop
// (core/coupled_stability.h), where the dashpot and the mass come back late with the force.

#include <vector>

#include "core/coupled_stability.h"
#include "core/stability.h"

namespace rths::core {

// The pre-run check of a lag (core::check_modal_critical_delay) for uncompensated parts whose
// specimens may carry a dashpot or a mass (the model's C and M leave them out): the modal and
// discrete limits on the whole structure (C_N + sum c_j b_j b_j', M_N + sum m_j b_j b_j', each
// part's dashpot and mass taken undelayed there, as the modal approximation states), the
// continuous limit the coupled loop's with every part at the lag (dashpot and mass late with its
// stiffness). Without a dashpot or a mass, exactly check_modal_critical_delay with K_e = sum
// k_j b_j b_j'. Parts' predictors and lags are ignored. Throws as both.
CriticalDelayCheck check_loop_critical_delay(const StructuralModel& model,
                                             std::vector<DelayedPart> parts, IntegratorKind kind,
                                             double dt, double lag);

}  // namespace rths::core
