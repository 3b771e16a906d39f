#pragma once
// The outputs and exit status of a study run (`run`, `sdof`, `launch`): the output folder
// claimed by its study, the table, plots and summary written, the benchmark's indices, and the
// failed cases named.
#include <filesystem>
#include <string>

#include "analysis/study_run/study_run.h"

namespace rths::cli {

// An output folder belongs to the study that first wrote it: its OUTPUT_OWNER file (kOwnerFile)
// names the study, or, in a folder written before that file, its summary.json's "study". Another
// study's folder is refused (ExitError kExitBadInput naming both studies, the folder and
// --force) unless `force`; then, or when the folder is new or this study's, the study claims it.
inline constexpr const char* kOwnerFile = ".rths-study";
void claim_output_folder(const std::filesystem::path& out, const std::string& study, bool force);

// results.csv and the plots (drawn at once; with plots off, plots of an earlier run are left in
// place and the summary names them), then summary.json/.txt; prints the summary (JSON or text)
// and "written:" with the files written. Figures that fail are a warning, not an error: the
// table and summary are written whatever gnuplot does, and the exit is the cases'.
void write_study_outputs(const analysis::StudyOutcome& outcome, const std::filesystem::path& out,
                         bool plots, bool json, const std::string& format = "csv");
// A study with a benchmark section: J1-J9 of its cases (analysis::evaluate_benchmark) written to
// out/benchmark.txt and out/benchmark.json, with `plots` its figures (analysis/benchmark/benchmark_plots.h),
// and the table printed unless `quiet`. Nothing without one. The same after `rths run` and
// `rths launch`.
void write_benchmark_outputs(const study::PreparedStudy& prepared,
                             const analysis::StudyOutcome& outcome,
                             const std::filesystem::path& out, bool plots, bool quiet);
// Throws ExitError(1) listing every case that failed the run (analysis::StudyOutcome::failures).
void fail_if_unstable(const analysis::StudyOutcome& outcome, bool allow_unstable);

}  // namespace rths::cli
