#pragma once
// The RTHS benchmark's figures for a study judged by its criteria (analysis/benchmark/benchmark_evaluation.h),
// as the benchmark's own evaluation code draws them, each PNG with an SVG beside it:
//   benchmark_criteria.png  J1 (ms) and J2-J9 (%) of every judged case, a bar per case and
//                           criterion, the published values (where they apply to this run's motion
//                           and structure) as black marks;
//   benchmark_floors.png    the displacement (mm) of the floors other than the experimental one (at
//                           most two: the benchmark's floors 2 and 3, those of J6-J9) against time,
//                           the exact response of the whole structure and every judged case that
//                           stayed bounded.
// Needs gnuplot (util/plot.h). Returns the PNGs written.

#include <filesystem>
#include <string>
#include <vector>

#include "analysis/benchmark/benchmark_evaluation.h"
#include "analysis/study_run/study_run.h"

namespace rths::analysis {

std::vector<std::string> benchmark_plot_files();  // PNG and SVG names, as written

std::vector<std::filesystem::path> write_benchmark_plots(const BenchmarkEvaluation& evaluation,
                                                         const StudyOutcome& outcome,
                                                         const std::filesystem::path& directory);

}  // namespace rths::analysis
