#pragma once
// Restoring-force models (core/restoring_force.h) from their config message: a factory that
// builds a storey's model from its initial stiffness (N/m). Linear when the message names none.
// Throws std::invalid_argument naming the field for a bad yield displacement or ratio.

#include "core/substructure.h"
#include "rths/proto/config.pb.h"

namespace rths::study {

core::StoreyModelFactory make_storey_factory(const config::RestoringForce& model);

}  // namespace rths::study
