#pragma once
// Compensation blocks (core/compensation.h) from their study config messages.

#include <memory>
#include <string>

#include "core/compensation.h"
#include "rths/proto/config.pb.h"

namespace rths::study {

// From a study config. `where` names the block in errors ("cases[3] 'ats' compensation[0]").
// validate_compensation checks what does not depend on dt; make_compensator builds the block,
// whose constructor checks what does (window or roll-off against dt) under the config path:
// "WHERE.adaptive_time_series: window ...". Both throw std::invalid_argument "WHERE.FIELD ...".
void validate_compensation(const config::Compensation& compensation, const std::string& where);
std::unique_ptr<core::Compensator> make_compensator(const config::Compensation& compensation,
                                                    double dt, const std::string& where);
// The actuator model a model-based compensator inverts, from delay stages (shift, first_order,
// transfer_function, benchmark; amplitude gains multiply). Other kinds cannot be inverted: throws.
core::PlantModel plant_from_stages(
    const google::protobuf::RepeatedPtrField<config::DelayStage>& stages, const std::string& where);

}  // namespace rths::study
