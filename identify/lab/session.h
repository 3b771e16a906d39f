#pragma once
// One identification as `rths identify` runs it on a lab record, from files to reports: the CLI
// only parses flags into a SessionRequest, calls run_session and prints session_text or
// session_json.
//
//   1. load the record (and --validate's), trimmed to its active part with trim_idle (data.h); a
//      record without a force column is read when the force channel is not asked for;
//   2. the declared model from `model` (a file, declared_model.h) where it declares a channel, else
//      from the options; a channel declared both ways is refused (one source of truth);
//   3. identify (identify.h) -> optionally predict a study with the identified actuator
//      (predict.h) and design a compensator from it (compensator_design.h);
//   4. with `out`: the identified model back as files (identified_model.textproto,
//      identified_study_fragment.textproto, identified_study.textproto with `predict`) and the
//      plots (report.h);
//   5. validation per channel: the in-record held-out error, the k-fold over contiguous blocks
//      (validation.h, every fold from the identified parameters, residuals at every 4th sample)
//      and, with `validate`, the error on another record of the rig.
// Errors: std::invalid_argument for bad input (files, flags, declared model: exit 2 in the CLI);
// std::runtime_error prefixed "outputs: " when an output cannot be written (exit 3).
// Progress: IdentifyProgress over the identification's units and one per fold and channel.

#include <nlohmann/json.hpp>

#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "identify/fit/identify.h"
#include "identify/fit/validation.h"
#include "identify/lab/compensator_design.h"
#include "identify/lab/predict.h"
#include "identify/model/data.h"

namespace rths::identify {

struct SessionRequest {
  std::string data;                // the record (CSV or DAQ export)
  std::string validate;            // another record of the same rig; empty = none
  std::string model;               // declared model file; empty = from `options`
  std::string predict;             // study config to run with the identified actuator; empty = none
  std::string out;                 // output directory; empty = no files
  std::string design_compensator;  // compensator kind (compensator_design.h); empty = none
  double design_dt = 0.001;        // s, the planned test's step
  CsvUnits units;
  std::string time_unit = "s", length_unit = "mm", force_unit = "N";  // their names, reported
  DaqColumnMap map;
  double sample_rate = 0.0;  // Hz; 0 = from the file
  bool trim_idle = false;
  std::size_t folds = 5;  // k-fold validation; < 2 = off
  // Whether the declared actuator / specimen were given apart from `model` (flags): conflicts.
  bool actuator_given = false, specimen_given = false;
  IdentifyOptions options;  // its `progress` is set by run_session
};

struct ChannelValidation {
  Channel channel = Channel::kMeasured;
  double in_record_heldout = 0.0;
  std::optional<KFoldResult> kfold;
  std::vector<double> jacobian_std_errors;  // of the final fit, one per parameter
  std::optional<CrossRecordResult> other;
};

struct SessionResult {
  Identification id;
  std::optional<StudyPrediction> prediction;
  std::optional<CompensatorDesign> compensator;
  std::filesystem::path compensator_file;
  std::vector<ChannelValidation> validation;
  std::vector<std::string> trimmed;          // what --trim-idle kept, per record
  std::vector<std::string> configs_written;  // "what: path" per file written back
};

SessionResult run_session(const SessionRequest& request,
                          const std::function<void(const IdentifyProgress&)>& progress = {});

// The report as `rths identify` prints it (text) and as --json prints it.
std::string session_text(const SessionResult& result, const SessionRequest& request,
                         const std::string& table_format);
nlohmann::json session_json(const SessionResult& result, const SessionRequest& request);

}  // namespace rths::identify
