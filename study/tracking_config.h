#pragma once
// Tracking-loop blocks (core/tracking.h) from their study config messages. Errors throw
// std::invalid_argument naming the config field ("cases[1].delay[0].tracking_loop.controller").

#include <string>

#include "core/tracking.h"
#include "rths/proto/stages.pb.h"

namespace rths::study {

// The filter of `spec` at step h: continuous (Tustin), discrete, state space, PID or phase lead.
core::DiscreteFilter make_filter(const config::DelayStage::LinearFilter& spec, double h,
                                 const std::string& field);

// The nominal benchmark plant of F1_input_file.m with the given fields overriding it (0 = nominal).
core::BenchmarkPlantParameters benchmark_plant_parameters(
    const config::DelayStage::BenchmarkPlant& spec);

// The loop of `spec` at step h: its plant (benchmark_plant or plant, zero-order-hold discretised),
// filters, converters, noises and force delay.
core::TrackingLoop make_tracking_loop(const config::DelayStage::TrackingLoop& spec, double h,
                                      const std::string& field);

}  // namespace rths::study
