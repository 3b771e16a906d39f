#pragma once
// Reports of an identification: a human-readable table, a JSON object and PNG plots.
//
// JSON (to_json): { "source", "samples", "dt", "search_decimation",
//   "holdout": {"mode", "fraction", "train_samples", "heldout_samples"},
//   "steps": [ {channel, effect, params: {name: {value, std_error, unit}}, train_error_before,
//               train_error_after, heldout_error_before, heldout_error_after, evidence: {...},
//               ranking: [{effect, train_error, heldout_error, score, pays}]} ... ],
//   "channels": [ {channel, declared, noise_floor, input_lowpass_hz (the specimen model's input
//                  low-pass, model.h make_signals; 0 = none), final: {effects, params, train_error,
//                  heldout_error}, final_evidence, rejected: [ranking of the round where nothing
//                  paid]} ],
//   "prediction": {...} when a study was predicted }
// `steps` lists the effects added, in order, measured channel first; clean data gives [].
// Errors are RMS(residual) / std(measured signal) over the training / held-out samples.
//
// Plots (write_plots), one set per channel into `directory`:
//   <channel>_residual_time.png       residual of the declared and of the final model against time
//   <channel>_residual_spectrum.png   their amplitude spectra (log scale)
//   force_loops.png                   measured force against measured displacement, with the
//                                     declared and the final model's force (a held-out window)
//   measured_tracking.png             command, measured and modelled displacement (a window)
//   measured_bode.png                 amplitude ratio (mm/mm) and phase (deg) against frequency
//                                     (Hz, log axis): measured H1 by Welch averaging against the
//                                     identified and the declared model's response, with the
//                                     coherence, over the band where it is >= 0.9 (bode.h); left
//                                     out when the record is too short or has no such band
// Every PNG has an SVG of the same figure beside it (util/plot.h).

#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "identify/fit/identify.h"
#include "identify/lab/predict.h"

namespace rths::identify {

struct ReportContext {
  double holdout_fraction = 0.3;
  HoldoutMode holdout_mode = HoldoutMode::kBlocks;
};

nlohmann::json to_json(const Identification& id, const ReportContext& context,
                       const std::optional<StudyPrediction>& prediction = std::nullopt);
std::string format_table(const Identification& id,
                         const std::optional<StudyPrediction>& prediction = std::nullopt);
// Returns the files written. Throws std::runtime_error naming the file (gnuplot missing, ...).
std::vector<std::filesystem::path> write_plots(const Identification& id,
                                               const std::filesystem::path& directory);

}  // namespace rths::identify
