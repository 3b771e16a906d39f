#include "identify/lab/session.h"

#include <sstream>
#include <stdexcept>

#include "identify/lab/report.h"
#include "identify/lab/report_plots.h"
#include "identify/model/declared_model.h"
#include "identify/model/study_config.h"
#include "study/study.h"
#include "study/text_format.h"

namespace rths::identify {
namespace {

// The record at `path`, cut to its active part with trim_idle (the note says what was kept).
MeasuredData load_record(const SessionRequest& request, const std::string& path,
                         std::vector<std::string>& trimmed) {
  MeasuredData record = read_measured(path, request.units, request.map, kDefaultMinSamples,
                                      request.sample_rate, force_column(request.options.channels));
  if (!request.trim_idle) return record;
  const ActiveRange active = active_range(record);
  std::ostringstream note;
  note << path << ": active part " << record.time[active.begin] << " s to "
       << record.time[active.end - 1] << " s of " << record.time.front() << " s to "
       << record.time.back() << " s (--trim-idle)";
  trimmed.push_back(note.str());
  MeasuredData active_part = slice(record, active.begin, active.end);
  active_part.source = record.source;
  validate(active_part, kDefaultMinSamples);
  return active_part;
}

// The declared model from the file where it declares a channel; the file's bounds are checked
// against the record's physics.
IdentifyOptions declared_options(const SessionRequest& request, const MeasuredData& data) {
  IdentifyOptions options = request.options;
  if (request.model.empty()) return options;
  const DeclaredModel declared = load_declared_model(request.model);
  if (declared.actuator) {
    if (request.actuator_given) {
      throw std::invalid_argument("--declared-actuator conflicts with --model " + request.model +
                                  ", which declares the actuator; give one of them");
    }
    options.declared_actuator = declared.actuator->effects;
    options.actuator_parameters = declared.actuator->parameters;
  }
  if (declared.specimen) {
    if (request.specimen_given) {
      throw std::invalid_argument("--declared-specimen conflicts with --model " + request.model +
                                  ", which declares the specimen; give one of them");
    }
    options.declared_specimen = declared.specimen->effects;
    options.specimen_parameters = declared.specimen->parameters;
  }
  for (const auto& [channel, part] : {std::pair{Channel::kMeasured, &declared.actuator},
                                      std::pair{Channel::kForce, &declared.specimen}}) {
    if (*part) {
      check_physical_bounds(**part, channel, signal_scales(make_signals(data, channel)),
                            declared.source);
    }
  }
  return options;
}

// The identified model written back (session.h step 4); returns "what: path" per file.
std::vector<std::string> write_identified_configs(const Identification& id,
                                                  const SessionRequest& request) {
  const std::filesystem::path dir = request.out;
  const ChannelModel* actuator = nullptr;
  const ChannelModel* specimen = nullptr;
  std::optional<ActuatorCase> actuator_part;
  std::optional<SpecimenModel> specimen_part;
  std::vector<std::string> notes;
  for (std::size_t k = 0; k < id.channels.size(); ++k) {
    const auto& model = id.channels[k].final_fit.model;
    const auto scales = signal_scales(id.signals[k]);
    if (model.channel == Channel::kMeasured) {
      actuator = &model;
      actuator_part = actuator_case(model, scales);
      for (const auto& n : actuator_part->left_out) notes.push_back("actuator: " + n);
    } else {
      specimen = &model;
      specimen_part = specimen_model(model, scales);
      notes.push_back("specimen: " + specimen_part->description);
      for (const auto& n : specimen_part->left_out) notes.push_back("specimen: " + n);
    }
  }
  std::vector<std::string> written;
  const auto model_path = dir / "identified_model.textproto";
  study::write_text_format(
      to_config(actuator, specimen), model_path,
      {"Identified by `rths identify " + request.data + "`: fitted values as initial values.",
       "Start another identification from it: rths identify DATA --model " + model_path.string()});
  written.push_back("identified model (reads back with --model): " + model_path.string());
  const config::Study fragment = study_fragment(actuator_part, specimen_part);
  std::vector<std::string> comment{
      "Identified by `rths identify " + request.data +
          "`: the parts of a study config it determines.",
      "Copy substructuring.model into a study's substructuring and append the cases block;",
      "`rths identify DATA --predict STUDY --out DIR` writes the whole study."};
  for (const auto& n : notes) comment.push_back(n);
  const auto fragment_path = dir / "identified_study_fragment.textproto";
  study::write_text_format(fragment, fragment_path, comment);
  written.push_back("study-config parts: " + fragment_path.string());
  if (!request.predict.empty()) {
    const std::filesystem::path base_path = request.predict;
    const config::Study study =
        identified_study(study::load_study(base_path), base_path.parent_path(), fragment);
    const auto study_path = dir / "identified_study.textproto";
    comment[1] = base_path.string() + " with the identified specimen model and the case '" +
                 std::string(kIdentifiedCaseName) + "'.";
    comment[2] = "Run it: rths run " + study_path.string();
    study::write_text_format(study, study_path, comment);
    written.push_back("study with the identified model (rths run): " + study_path.string());
  }
  return written;
}

// The identified actuator; throws naming `what` needs it when the channel was not identified.
const ChannelModel& actuator_of(const Identification& id, const std::string& what) {
  const auto* actuator = id.find(Channel::kMeasured);
  if (actuator == nullptr) throw std::invalid_argument(what);
  return actuator->final_fit.model;
}

void predict_and_design(const SessionRequest& request, SessionResult& result) {
  const Identification& id = result.id;
  if (!request.predict.empty()) {
    const ChannelModel& actuator =
        actuator_of(id, "--predict needs the 'measured' channel in --channels");
    result.prediction = predict_study(request.predict, actuator, signal_scales(id.signals.front()));
  }
  if (request.design_compensator.empty()) return;
  const ChannelModel& actuator = actuator_of(
      id, "--design-compensator needs the actuator model: include 'measured' in --channels");
  result.compensator =
      design_compensator(actuator, signal_scales(id.signals.front()),
                         parse_compensator_kind(request.design_compensator), request.design_dt);
  try {
    result.compensator_file = write_compensator_case(*result.compensator, request.out);
  } catch (const std::runtime_error& e) {
    throw std::runtime_error(e.what());
  }
}

void write_outputs(const SessionRequest& request, SessionResult& result) {
  if (request.out.empty()) return;
  try {
    result.configs_written = write_identified_configs(result.id, request);
  } catch (const std::runtime_error& e) {
    throw std::runtime_error(std::string("outputs: ") + e.what());
  }
  try {
    write_plots(result.id, request.out);
  } catch (const std::exception& e) {
    throw std::runtime_error(std::string("outputs: ") + e.what());
  }
}

// Session step 5 for every channel; `report` is given the folds done over all channels.
std::vector<ChannelValidation> validate_channels(
    const SessionRequest& request, const Identification& id,
    const std::optional<MeasuredData>& other,
    const std::function<void(std::size_t, const std::string&)>& report) {
  std::vector<ChannelValidation> out;
  for (std::size_t k = 0; k < id.channels.size(); ++k) {
    const auto& c = id.channels[k];
    ChannelValidation v;
    v.channel = c.channel;
    v.in_record_heldout = c.final_fit.heldout_error;
    v.jacobian_std_errors = c.final_fit.std_errors;
    if (request.folds >= 2) {
      const std::string stage = channel_name(c.channel) + ": k-fold validation";
      std::size_t done = k * request.folds;
      FitOptions fast;
      fast.stride = 4;
      fast.on_iteration = [&] { report(done, stage); };
      v.kfold =
          kfold(c.final_fit.model, id.signals[k], request.folds, fast, [&](std::size_t folds) {
            done = k * request.folds + folds;
            report(done, stage);
          });
    }
    if (other) {
      v.other = validate_on(c.final_fit.model, make_signals(*other, c.channel), other->source);
    }
    out.push_back(std::move(v));
  }
  return out;
}

}  // namespace

SessionResult run_session(const SessionRequest& request,
                          const std::function<void(const IdentifyProgress&)>& progress) {
  SessionResult result;
  const MeasuredData data = load_record(request, request.data, result.trimmed);
  std::optional<MeasuredData> other;  // read first: a bad file fails before the fit
  if (!request.validate.empty()) other = load_record(request, request.validate, result.trimmed);
  IdentifyOptions options = declared_options(request, data);
  const std::size_t fold_units = request.folds >= 2 ? request.folds * options.channels.size() : 0;
  const std::size_t identify_total = identify_units(options);
  const std::size_t total = identify_total + fold_units;
  const auto report = [&](std::size_t done, const std::string& stage) {
    if (progress) progress({done, total, stage});
  };
  options.progress = [&](const IdentifyProgress& p) { report(p.done, p.stage); };
  result.id = identify(data, options);
  report(identify_total, "identified");
  predict_and_design(request, result);
  write_outputs(request, result);
  result.validation = validate_channels(
      request, result.id, other,
      [&](std::size_t done, const std::string& stage) { report(identify_total + done, stage); });
  return result;
}

}  // namespace rths::identify

namespace rths::identify {
namespace {

nlohmann::json validation_json(const ChannelValidation& v, std::size_t folds) {
  nlohmann::json entry = {{"channel", channel_name(v.channel)},
                          {"in_record_heldout_error", v.in_record_heldout}};
  if (v.kfold) {
    const KFoldResult& f = *v.kfold;
    nlohmann::json params = nlohmann::json::object();
    for (std::size_t p = 0; p < f.param_names.size(); ++p) {
      params[f.param_names[p]] = {{"mean", f.param_mean[p]},
                                  {"fold_spread", f.param_spread[p]},
                                  {"jacobian_std_error", v.jacobian_std_errors.at(p)}};
    }
    // validation.h: every fold by the record's std; spread = sample standard deviation.
    entry["kfold"] = {{"folds", folds},
                      {"normalised_by", "std of the target over the whole record"},
                      {"heldout_errors", f.heldout_errors},
                      {"heldout_errors_by_block_std", f.block_errors},
                      {"noise_floors", f.noise_floors},
                      {"mean", f.mean},
                      {"spread", f.spread},
                      {"params", params}};
  }
  if (v.other) entry["other_record"] = {{"source", v.other->source}, {"error", v.other->error}};
  return entry;
}

std::string validation_text(const ChannelValidation& v, std::size_t folds) {
  std::ostringstream text;
  text << "validation of channel " << channel_name(v.channel) << ": in-record held-out "
       << 100.0 * v.in_record_heldout << " %";
  if (v.kfold) {
    const KFoldResult& f = *v.kfold;
    text << "; " << folds << "-fold " << 100.0 * f.mean << " +/- " << 100.0 * f.spread
         << " % (of the record's std; +/- one sample standard deviation; folds";
    for (std::size_t i = 0; i < f.heldout_errors.size(); ++i) {
      text << (i ? ", " : " ") << 100.0 * f.heldout_errors[i] << " % (floor ";
      // evidence.h: 0 when the block has no band free of signal to estimate the noise from.
      if (f.noise_floors[i] > 0.0) {
        text << 100.0 * f.noise_floors[i] << " %)";
      } else {
        text << "n/a)";
      }
    }
    text << ")";
  }
  if (v.other) {
    text << "; on " << v.other->source << " " << 100.0 * v.other->error
         << " % (offsets and drifts re-estimated)";
  }
  text << "\n";
  return text.str();
}

}  // namespace

std::string session_text(const SessionResult& result, const SessionRequest& request,
                         const std::string& table_format) {
  std::ostringstream out;
  out << "input units: time " << request.time_unit << ", length " << request.length_unit
      << ", force " << request.force_unit << " (--time-unit, --length-unit, --force-unit)\n";
  for (const auto& line : result.trimmed) out << line << "\n";
  out << format_table(result.id, result.prediction);
  for (const auto& v : result.validation) out << validation_text(v, request.folds);
  if (!request.out.empty()) {
    out << "plots and identify." << table_format << " written to " << request.out << "\n";
  }
  for (const auto& line : result.configs_written) out << line << "\n";
  return out.str();
}

nlohmann::json session_json(const SessionResult& result, const SessionRequest& request) {
  const ReportContext context{request.options.holdout_fraction, request.options.holdout_mode};
  nlohmann::json report = to_json(result.id, context, result.prediction);
  report["input_units"] = {
      {"time", request.time_unit}, {"length", request.length_unit}, {"force", request.force_unit}};
  nlohmann::json validation = nlohmann::json::array();
  for (const auto& v : result.validation) validation.push_back(validation_json(v, request.folds));
  report["validation"] = validation;
  if (!result.configs_written.empty()) report["configs_written"] = result.configs_written;
  if (request.trim_idle) report["trimmed"] = result.trimmed;
  return report;
}

}  // namespace rths::identify
