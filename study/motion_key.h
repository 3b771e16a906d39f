#pragma once
// A motion's key: SHA-256 of the motion as run, dt then the samples (m/s^2) as IEEE doubles, as
// 64 lower-case hex digits. What benchmark.published_motion_sha256 and every run's table
// (motion_sha256, results/results.h) name a motion by: the same for a run and for its record,
// which embeds the motion as run; the name and description do not count.

#include <string>

#include "core/ground_motion.h"

namespace rths::study {

std::string motion_key(const core::GroundMotion& motion);

}  // namespace rths::study
