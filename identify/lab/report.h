#pragma once
// Reports of an identification: a human-readable table and a JSON object (its plots:
// report_plots.h).
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
// `v` with 4 significant digits ("0.01234"): how the table and the plots' titles print a value.
std::string format_value(double v);

}  // namespace rths::identify
