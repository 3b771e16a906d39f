#pragma once
// The joint-lag study's figures (analysis/joint_lag/joint_lag.h): the error map over network x actuator lag
// with its contour levels, diverged and past-the-boundary points and the stability boundary
// (error_map.png/.svg, with its data files beside it), and the total lag measured across sites
// against the injected parts (total_lag.png/.svg). Drawn through util/plot.h; complete or absent.

#include <filesystem>

#include "analysis/joint_lag/joint_lag_result.h"

namespace rths::analysis {

void write_error_map(const JointLagResult& result, const std::filesystem::path& out);
void write_total_lag_png(const JointLagResult& result, const std::filesystem::path& out);

}  // namespace rths::analysis
