// `rths identify`: measured lab data -> declared model -> residual -> missing effects -> refit,
// with the error before and after on held-out data; optionally the identified actuator is put
// back into a study config's simulation (--predict) to predict the test's error. The declared
// model comes from flags or a file (--model, identify/declared_model.h); --out writes the
// identified model back as such a file and as study-config parts (identify/study_config.h).
#include <nlohmann/json.hpp>

#include <filesystem>
#include <iostream>
#include <memory>
#include <optional>
#include <sstream>

#include "cli/commands.h"
#include "cli/support.h"
#include "core/study.h"
#include "core/text_format.h"
#include "identify/compensator_design.h"
#include "identify/declared_model.h"
#include "identify/data.h"
#include "identify/identify.h"
#include "identify/predict.h"
#include "identify/report.h"
#include "identify/study_config.h"
#include "tables/results.h"
#include "tables/write.h"
#include "identify/validation.h"

namespace rths::cli {
namespace {

struct IdentifyCliOptions {
  std::string data, column_map, time_unit = "s", length_unit = "mm", force_unit = "N";
  std::string channels = "measured,force", declared_actuator = "delay",
              declared_specimen = "stiffness", candidates, holdout_mode = "blocks";
  std::string out, predict, design_compensator, validate, model;
  // Whether the declared-model flags were given on the command line (not just their defaults).
  bool actuator_flag_given = false, specimen_flag_given = false;
  double sample_rate = 0.0;  // Hz; 0 = from the file
  std::string format = "csv";  // of <out>/identify.<ext>: the record and both models' predictions
  double design_dt = 0.001;
  std::size_t folds = 5;
  double holdout = 0.3, min_improvement = 0.05, penalty = 0.01;
  std::size_t blocks = 10, max_steps = 6, decimate = 0, search_samples = 12000;
  bool json = false, trim_idle = false;
};

std::vector<std::string> split_list(const std::string& text) {
  std::vector<std::string> out;
  std::stringstream stream(text);
  std::string item;
  while (std::getline(stream, item, ',')) {
    if (!item.empty() && item != "none") out.push_back(item);
  }
  return out;
}

std::vector<identify::Effect> effects_for(const std::string& list, identify::Channel channel,
                                          const std::string& flag) {
  std::vector<identify::Effect> out;
  for (const auto& name : split_list(list)) {
    const identify::Effect e = identify::parse_effect(name);
    if (!identify::effect_applies(e, channel)) {
      throw std::invalid_argument(flag + ": effect '" + name + "' does not apply to channel '" +
                                  identify::channel_name(channel) + "'");
    }
    out.push_back(e);
  }
  return out;
}

// The declared model from --model FILE where it declares a channel, else from the flags. A
// channel declared both ways is refused: one source of truth.
void apply_declared_model(const IdentifyCliOptions& o, identify::IdentifyOptions& options,
                          std::optional<identify::DeclaredModel>& declared) {
  if (o.model.empty()) return;
  declared = identify::load_declared_model(o.model);
  if (declared->actuator) {
    if (o.actuator_flag_given) {
      throw std::invalid_argument("--declared-actuator conflicts with --model " + o.model +
                                  ", which declares the actuator; give one of them");
    }
    options.declared_actuator = declared->actuator->effects;
    options.actuator_parameters = declared->actuator->parameters;
  }
  if (declared->specimen) {
    if (o.specimen_flag_given) {
      throw std::invalid_argument("--declared-specimen conflicts with --model " + o.model +
                                  ", which declares the specimen; give one of them");
    }
    options.declared_specimen = declared->specimen->effects;
    options.specimen_parameters = declared->specimen->parameters;
  }
}

// DIR/identified_model.textproto (reads back with --model), DIR/identified_study_fragment.textproto
// (the study-config parts) and, with a study (--predict), DIR/identified_study.textproto (that
// study with the identified specimen and actuator, for `rths run`). Returns the lines to print.
std::vector<std::string> write_identified_configs(const identify::Identification& id,
                                                  const IdentifyCliOptions& o) {
  const std::filesystem::path dir = o.out;
  const identify::ChannelModel* actuator = nullptr;
  const identify::ChannelModel* specimen = nullptr;
  std::optional<identify::ActuatorCase> actuator_case;
  std::optional<identify::SpecimenModel> specimen_model;
  std::vector<std::string> notes;
  for (std::size_t k = 0; k < id.channels.size(); ++k) {
    const auto& model = id.channels[k].final_fit.model;
    const auto scales = identify::signal_scales(id.signals[k]);
    if (model.channel == identify::Channel::kMeasured) {
      actuator = &model;
      actuator_case = identify::actuator_case(model, scales);
      for (const auto& n : actuator_case->left_out) notes.push_back("actuator: " + n);
    } else {
      specimen = &model;
      specimen_model = identify::specimen_model(model, scales);
      notes.push_back("specimen: " + specimen_model->description);
      for (const auto& n : specimen_model->left_out) notes.push_back("specimen: " + n);
    }
  }
  std::vector<std::string> written;
  const auto model_path = dir / "identified_model.textproto";
  core::write_text_format(identify::to_config(actuator, specimen), model_path,
                          {"Identified by `rths identify " + o.data + "`: fitted values as initial values.",
                           "Start another identification from it: rths identify DATA --model " +
                               model_path.string()});
  written.push_back("identified model (reads back with --model): " + model_path.string());
  const config::Study fragment = identify::study_fragment(actuator_case, specimen_model);
  std::vector<std::string> comment{
      "Identified by `rths identify " + o.data + "`: the parts of a study config it determines.",
      "Copy substructuring.model into a study's substructuring and append the cases block;",
      "`rths identify DATA --predict STUDY --out DIR` writes the whole study."};
  for (const auto& n : notes) comment.push_back(n);
  const auto fragment_path = dir / "identified_study_fragment.textproto";
  core::write_text_format(fragment, fragment_path, comment);
  written.push_back("study-config parts: " + fragment_path.string());
  if (!o.predict.empty()) {
    const std::filesystem::path base_path = o.predict;
    const config::Study study = identify::identified_study(core::load_study(base_path),
                                                           base_path.parent_path(), fragment);
    const auto study_path = dir / "identified_study.textproto";
    comment[1] = base_path.string() + " with the identified specimen model and the case '" +
                 std::string(identify::kIdentifiedCaseName) + "'.";
    comment[2] = "Run it: rths run " + study_path.string();
    core::write_text_format(study, study_path, comment);
    written.push_back("study with the identified model (rths run): " + study_path.string());
  }
  return written;
}

void run_identify(const IdentifyCliOptions& o) {
  identify::CsvUnits units;
  units.time_to_s = identify::time_unit_to_s(o.time_unit);
  units.length_to_m = identify::length_unit_to_m(o.length_unit);
  units.force_to_n = identify::force_unit_to_n(o.force_unit);
  const identify::DaqColumnMap map = identify::parse_column_map(o.column_map);

  identify::IdentifyOptions options;
  options.channels.clear();
  for (const auto& name : split_list(o.channels)) {
    if (name == "measured") options.channels.push_back(identify::Channel::kMeasured);
    else if (name == "force") options.channels.push_back(identify::Channel::kForce);
    else throw std::invalid_argument("--channels: unknown channel '" + name + "' (measured, force)");
  }
  if (options.channels.empty()) throw std::invalid_argument("--channels: no channel given");
  options.declared_actuator =
      effects_for(o.declared_actuator, identify::Channel::kMeasured, "--declared-actuator");
  options.declared_specimen =
      effects_for(o.declared_specimen, identify::Channel::kForce, "--declared-specimen");
  for (const auto& name : split_list(o.candidates)) {
    options.selection.candidates.push_back(identify::parse_effect(name));
  }
  options.holdout_fraction = o.holdout;
  options.holdout_mode = identify::parse_holdout_mode(o.holdout_mode);
  options.holdout_blocks = o.blocks;
  options.search_decimation = o.decimate;
  options.search_samples = o.search_samples;
  options.selection.min_relative_improvement = o.min_improvement;
  options.selection.penalty_per_parameter = o.penalty;
  options.selection.max_steps = o.max_steps;

  std::optional<identify::DeclaredModel> declared;
  apply_declared_model(o, options, declared);

  // With --trim-idle, the idle stretches before and after the test are cut off (data.h).
  std::vector<std::string> trimmed;
  const auto load = [&](const std::string& path) {
    identify::MeasuredData record =
        identify::read_measured(path, units, map, identify::kDefaultMinSamples, o.sample_rate);
    if (!o.trim_idle) return record;
    const identify::ActiveRange active = identify::active_range(record);
    std::ostringstream note;
    note << path << ": active part " << record.time[active.begin] << " s to "
         << record.time[active.end - 1] << " s of " << record.time.front() << " s to "
         << record.time.back() << " s (--trim-idle)";
    trimmed.push_back(note.str());
    identify::MeasuredData active_part = identify::slice(record, active.begin, active.end);
    active_part.source = record.source;
    identify::validate(active_part, identify::kDefaultMinSamples);
    return active_part;
  };
  const identify::MeasuredData data = load(o.data);
  std::optional<identify::MeasuredData> other;  // read first: a bad file fails before the fit
  if (!o.validate.empty()) other = load(o.validate);
  if (declared) {
    for (const auto& [channel, part] :
         {std::pair{identify::Channel::kMeasured, &declared->actuator},
          std::pair{identify::Channel::kForce, &declared->specimen}}) {
      if (*part) {
        identify::check_physical_bounds(
            **part, channel, identify::signal_scales(identify::make_signals(data, channel)),
            declared->source);
      }
    }
  }
  // Progress on stderr (cli/support.h): the identification's units, then one per k-fold fit.
  ProgressReporter progress("identify", "steps");
  const std::size_t fold_units = o.folds >= 2 ? o.folds * options.channels.size() : 0;
  const std::size_t identify_units = identify::identify_units(options);
  options.progress = [&](const identify::IdentifyProgress& p) {
    progress.update(p.done, p.total + fold_units);
  };
  const identify::Identification id = identify::identify(data, options);
  progress.update(identify_units, identify_units + fold_units);

  std::optional<identify::StudyPrediction> prediction;
  if (!o.predict.empty()) {
    const auto* actuator = id.find(identify::Channel::kMeasured);
    if (actuator == nullptr) {
      throw std::invalid_argument("--predict needs the 'measured' channel in --channels");
    }
    const auto scales = identify::signal_scales(id.signals.front());
    prediction = identify::predict_study(o.predict, actuator->final_fit.model, scales);
  }
  if (!o.design_compensator.empty()) {
    const auto* actuator = id.find(identify::Channel::kMeasured);
    if (actuator == nullptr) {
      throw std::invalid_argument("--design-compensator needs the actuator model: include 'measured' in --channels");
    }
    const auto design = identify::design_compensator(
        actuator->final_fit.model, identify::signal_scales(id.signals.front()),
        identify::parse_compensator_kind(o.design_compensator), o.design_dt);
    std::filesystem::path written;
    try {
      written = identify::write_compensator_case(design, o.out);
    } catch (const std::runtime_error& e) {
      throw ExitError(kExitEnvironment, e.what());
    }
    std::cerr << "compensator: " << design.summary << "\nwritten to " << written.string() << "\n";
  }
  std::vector<std::string> configs_written;
  if (!o.out.empty()) {
    try {
      configs_written = write_identified_configs(id, o);
    } catch (const std::runtime_error& e) {
      throw ExitError(kExitEnvironment, std::string("outputs: ") + e.what());
    }
    try {
      identify::write_plots(id, o.out);
      const tables::Format format = tables::parse_format(o.format);
      tables::write_table(tables::identify_table(id), std::filesystem::path(o.out) / ("identify" + tables::extension(format)), format);
    } catch (const std::exception& e) {
      throw ExitError(kExitEnvironment, std::string("outputs: ") + e.what());
    }
  }
  // Validation: k-fold over contiguous blocks and, with --validate, another record of the rig.
  nlohmann::json validation = nlohmann::json::array();
  std::ostringstream validation_text;
  for (std::size_t k = 0; k < id.channels.size(); ++k) {
    const auto& c = id.channels[k];
    const auto& model = c.final_fit.model;
    nlohmann::json entry = {{"channel", identify::channel_name(c.channel)},
                            {"in_record_heldout_error", c.final_fit.heldout_error}};
    validation_text << "validation of channel " << identify::channel_name(c.channel)
                    << ": in-record held-out " << 100.0 * c.final_fit.heldout_error << " %";
    if (o.folds >= 2) {
      identify::FitOptions fast;
      fast.stride = 4;
      const auto folds = identify::kfold(model, id.signals[k], o.folds, fast, [&](std::size_t done) {
        progress.update(identify_units + k * o.folds + done, identify_units + fold_units);
      });
      nlohmann::json params = nlohmann::json::object();
      for (std::size_t p = 0; p < folds.param_names.size(); ++p) {
        params[folds.param_names[p]] = {{"mean", folds.param_mean[p]},
                                        {"fold_spread", folds.param_spread[p]},
                                        {"jacobian_std_error", c.final_fit.std_errors.at(p)}};
      }
      // identify/validation.h: every fold by the record's std; spread = sample standard deviation.
      entry["kfold"] = {{"folds", o.folds},
                        {"normalised_by", "std of the target over the whole record"},
                        {"heldout_errors", folds.heldout_errors},
                        {"heldout_errors_by_block_std", folds.block_errors},
                        {"noise_floors", folds.noise_floors},
                        {"mean", folds.mean},
                        {"spread", folds.spread},
                        {"params", params}};
      validation_text << "; " << o.folds << "-fold " << 100.0 * folds.mean << " +/- "
                      << 100.0 * folds.spread
                      << " % (of the record's std; +/- one sample standard deviation; folds";
      for (std::size_t f = 0; f < folds.heldout_errors.size(); ++f) {
        validation_text << (f ? ", " : " ") << 100.0 * folds.heldout_errors[f] << " % (floor ";
        // evidence.h: 0 when the block has no band free of signal to estimate the noise from.
        if (folds.noise_floors[f] > 0.0) {
          validation_text << 100.0 * folds.noise_floors[f] << " %)";
        } else {
          validation_text << "n/a)";
        }
      }
      validation_text << ")";
    }
    if (other) {
      const auto result = identify::validate_on(
          model, identify::make_signals(*other, c.channel), other->source);
      entry["other_record"] = {{"source", result.source}, {"error", result.error}};
      validation_text << "; on " << result.source << " " << 100.0 * result.error
                      << " % (offsets and drifts re-estimated)";
    }
    validation_text << "\n";
    validation.push_back(entry);
  }
  if (o.json) {
    const identify::ReportContext context{o.holdout, options.holdout_mode};
    nlohmann::json report = identify::to_json(id, context, prediction);
    report["input_units"] = {{"time", o.time_unit}, {"length", o.length_unit}, {"force", o.force_unit}};
    report["validation"] = validation;
    if (!configs_written.empty()) report["configs_written"] = configs_written;
    if (o.trim_idle) report["trimmed"] = trimmed;
    std::cout << report.dump(2) << "\n";
  } else {
    std::cout << "input units: time " << o.time_unit << ", length " << o.length_unit << ", force "
              << o.force_unit << " (--time-unit, --length-unit, --force-unit)\n";
    for (const auto& line : trimmed) std::cout << line << "\n";
    std::cout << identify::format_table(id, prediction) << validation_text.str();
    if (!o.out.empty()) std::cout << "plots and identify." << o.format << " written to " << o.out << "\n";
    for (const auto& line : configs_written) std::cout << line << "\n";
  }
}

}  // namespace

void add_identify_command(CLI::App& app) {
  auto o = std::make_shared<IdentifyCliOptions>();
  CLI::App* cmd = app.add_subcommand(
      "identify", "Find the effects a declared actuator/specimen model lacks in measured data");
  cmd->add_option("data", o->data,
                  "CSV time,command,measured,force or a raw DAQ export (Header Size: ...)")
      ->required();
  cmd->add_option("--time-unit", o->time_unit, "CSV time unit: s | ms");
  cmd->add_option("--length-unit", o->length_unit,
                  "CSV displacement unit: m | mm | cm | in (default mm; echoed in every report)");
  cmd->add_option("--force-unit", o->force_unit, "CSV force unit: N | kN | lbf | kip");
  cmd->add_option("--column-map", o->column_map,
                  "DAQ columns and scales to mm / N, e.g. "
                  "command=CHANNEL2*10,measured=CHANNEL0*10,force=CHANNEL1*9806.65 (the default)");
  cmd->add_option("--channels", o->channels, "channels to identify: measured,force");
  CLI::Option* actuator_flag = cmd->add_option(
      "--declared-actuator", o->declared_actuator,
      "declared actuator effects (gain is always there), comma list or none");
  CLI::Option* specimen_flag = cmd->add_option("--declared-specimen", o->declared_specimen,
                                               "declared specimen effects, comma list or none");
  cmd->add_option("--model", o->model,
                  "declared model file (text-format rths.config.DeclaredModel, proto/identify.proto): "
                  "actuator stages, specimen kind, each parameter's initial value, min, max, fixed; "
                  "replaces --declared-actuator / --declared-specimen for the channels it declares");
  cmd->add_option("--sample-rate", o->sample_rate,
                  "sampling rate (Hz) of a file without a time column (CSV without `time`, DAQ "
                  "export without Sampling Interval/Rate); checked against the file's own when both")
      ->check(in_range(core::Quantity::kFrequency));
  cmd->add_option("--candidates", o->candidates, "candidate effects (default: the whole library)");
  cmd->add_option("--holdout", o->holdout, "held-out share of the record")
      ->check(CLI::Range(0.01, 0.99));
  cmd->add_option("--holdout-mode", o->holdout_mode, "blocks (segment-wise) | last")
      ->check(CLI::IsMember({"blocks", "last"}));
  cmd->add_option("--blocks", o->blocks, "number of segments for --holdout-mode blocks")
      ->check(CLI::Range(2, 1000));
  cmd->add_option("--min-improvement", o->min_improvement,
                  "relative fall of the held-out error an effect must bring")
      ->check(CLI::Range(0.0, 1.0));
  cmd->add_option("--penalty", o->penalty, "relative penalty per added parameter")
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--max-steps", o->max_steps, "at most this many effects per channel")->check(in_range(core::Quantity::kCount));
  cmd->add_option("--decimate", o->decimate, "decimation for the search (0: automatic)");
  cmd->add_option("--search-samples", o->search_samples,
                  "automatic decimation keeps at most about this many samples")
      ->check(in_range(core::Quantity::kCount));
  cmd->add_option("--out", o->out, "directory for PNG plots with an SVG beside each (gnuplot; among them measured_bode.png, the actuator's amplitude ratio and phase, measured by Welch H1 against the models, over the band where the coherence >= 0.9), identify.<format> (the record and the declared and final models' predictions), identified_model.textproto (for --model), identified_study_fragment.textproto (study-config parts) and, with --predict, identified_study.textproto (for rths run)");
  cmd->add_option("--format", o->format, "identify.csv, identify.mat (MATLAB) or identify.h5 (HDF5) in --out")
      ->check(CLI::IsMember({"csv", "mat", "h5"}));
  cmd->add_option("--predict", o->predict,
                  "study config to run with the identified actuator (e.g. configs/paper_frame.textproto); "
                  "with --out, also written back with the identified model as identified_study.textproto");
  cmd->add_option("--design-compensator", o->design_compensator,
                  "write a compensator designed from the identified actuator to --out: "
                  "polynomial | ats | model-based | model-based-adaptive")
      ->check(CLI::IsMember({"polynomial", "ats", "model-based", "model-based-adaptive"}));
  cmd->add_option("--design-dt", o->design_dt, "integration step of the planned test (s, or 1ms)")
      ->transform(seconds_in(core::Quantity::kStep));
  cmd->add_option("--folds", o->folds,
                  "k-fold validation over contiguous blocks of the final model (0: off)");
  cmd->add_option("--validate", o->validate,
                  "another record of the same rig: the identified models' error on it");
  cmd->add_flag("--trim-idle", o->trim_idle,
                "cut the idle stretches before and after the test off the record(s): keep from "
                "0.25 s before the command first leaves its rest by 5 % of its peak to 0.25 s after "
                "it last does");
  cmd->add_flag("--json", o->json, "print the steps and models as JSON");
  cmd->callback([o, actuator_flag, specimen_flag] {
    o->actuator_flag_given = actuator_flag->count() > 0;
    o->specimen_flag_given = specimen_flag->count() > 0;
    if (!o->design_compensator.empty() && o->out.empty()) {
      throw std::invalid_argument("--design-compensator needs --out DIR");
    }
    run_identify(*o);
  });
}

}  // namespace rths::cli
