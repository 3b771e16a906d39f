// `rths identify`: measured lab data -> declared model -> residual -> missing effects -> refit,
// with the error before and after on held-out data; optionally the identified actuator is put
// back into a study config's simulation (--predict) to predict the test's error. The declared
// model comes from flags or a file (--model, identify/model/declared_model.h); --out writes the
// identified model back as such a file and as study-config parts (identify/model/study_config.h).
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <optional>
#include <sstream>

#include "cli/commands.h"
#include "cli/support.h"
#include "identify/fit/request.h"
#include "identify/lab/session.h"
#include "identify/run/run_config.h"
#include "identify/run/run_record.h"
#include "identify/run/run_record_format.h"
#include "identify/run/run_report.h"
#include "results/results.h"
#include "results/write.h"

namespace rths::cli {
namespace {

struct IdentifyCliOptions {
  std::string data, column_map, time_unit = "s", length_unit = "mm", force_unit = "N";
  identify::IdentifyRequest request;  // the identification's own options (identify/fit/request.h)
  std::string out, predict, design_compensator, validate, model;
  // Whether the declared-model flags were given on the command line (not just their defaults).
  bool actuator_flag_given = false, specimen_flag_given = false;
  double sample_rate = 0.0;    // Hz; 0 = from the file
  std::string format = "csv";  // of <out>/identify.<ext>: the record and both models' predictions
  double design_dt = 0.001;
  std::size_t folds = 5;
  bool json = false, trim_idle = false;
};

// "declared_actuator" -> "--declared-actuator": the flag of an IdentifyRequest field.
std::string flag_name(const std::string& field) {
  std::string flag = "--";
  for (char ch : field) flag += ch == '_' ? '-' : ch;
  return flag;
}

// Progress on stderr: the bar or one line per 10 % (cli/support.h), and what is being fitted
// ("force: candidate bouc_wen (round 2)") on a line of its own when it has changed and 2 s have
// passed since the last such line, or 5 s have passed: a long fit always says what it is doing.
class IdentifyProgressPrinter {
 public:
  void operator()(const identify::IdentifyProgress& p) {
    bar_.update(p.done, p.total);
    const auto now = std::chrono::steady_clock::now();
    const auto quiet = now - last_line_;
    if (quiet < std::chrono::seconds(2) ||
        (p.stage == last_stage_ && quiet < std::chrono::seconds(5))) {
      return;
    }
    last_stage_ = p.stage;
    last_line_ = now;
    // On a terminal the line replaces the bar, which the next update draws again below it.
    std::cerr << (tty_ ? "\r\033[K" : "") << "  fitting " << p.stage << " ("
              << std::chrono::duration<double>(now - start_).count() << " s)\n";
  }

 private:
  ProgressReporter bar_{"identify", "steps"};
  bool tty_ = isatty(fileno(stderr)) != 0;
  std::string last_stage_;
  std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now(),
                                        last_line_ = start_;
};

identify::SessionRequest session_request(const IdentifyCliOptions& o) {
  identify::SessionRequest r;
  r.data = o.data;
  r.validate = o.validate;
  r.model = o.model;
  r.predict = o.predict;
  r.out = o.out;
  r.design_compensator = o.design_compensator;
  r.design_dt = o.design_dt;
  r.units.time_to_s = identify::time_unit_to_s(o.time_unit);
  r.units.length_to_m = identify::length_unit_to_m(o.length_unit);
  r.units.force_to_n = identify::force_unit_to_n(o.force_unit);
  r.time_unit = o.time_unit;
  r.length_unit = o.length_unit;
  r.force_unit = o.force_unit;
  r.map = identify::parse_column_map(o.column_map);
  r.sample_rate = o.sample_rate;
  r.trim_idle = o.trim_idle;
  r.folds = o.folds;
  r.actuator_given = o.actuator_flag_given;
  r.specimen_given = o.specimen_flag_given;
  r.options = identify::identify_options(o.request, flag_name);
  return r;
}

// RECORD.rthsrec: a distributed run identified link by link (identify/run/run_record.h).
void run_identify_record(const IdentifyCliOptions& o, const identify::IdentifyOptions& options) {
  IdentifyProgressPrinter progress;
  identify::IdentifyOptions with_progress = options;
  with_progress.progress = [&](const identify::IdentifyProgress& p) { progress(p); };
  const identify::RunIdentification run = identify::identify_run_record(o.data, with_progress);
  if (!o.out.empty()) {
    try {
      for (const auto& line : identify::write_identified_run(
               run, std::filesystem::path(o.data).parent_path(), o.out)) {
        std::cerr << line << "\n";
      }
      for (const auto& png : identify::write_run_plots(run, o.out)) {
        std::cerr << "plot: " << png.string() << " (and .svg)\n";
      }
    } catch (const std::runtime_error& e) {
      throw ExitError(kExitEnvironment, std::string("outputs: ") + e.what());
    }
  }
  if (o.json) {
    std::cout << identify::run_record_json(run).dump(2) << "\n";
  } else {
    std::cout << identify::run_record_text(run);
  }
}

void run_identify(const IdentifyCliOptions& o) {
  const identify::SessionRequest request = session_request(o);
  if (identify::is_run_record(o.data)) return run_identify_record(o, request.options);
  IdentifyProgressPrinter progress;
  const identify::SessionResult result =
      identify::run_session(request, [&](const identify::IdentifyProgress& p) { progress(p); });
  if (result.compensator) {
    std::cerr << "compensator: " << result.compensator->summary << "\nwritten to "
              << result.compensator_file.string() << "\n";
  }
  if (!o.out.empty()) {
    try {
      const results::Format format = results::parse_format(o.format);
      results::write_table(results::identify_table(result.id),
                           std::filesystem::path(o.out) / ("identify" + results::extension(format)),
                           format);
    } catch (const std::exception& e) {
      throw ExitError(kExitEnvironment, std::string("outputs: ") + e.what());
    }
  }
  if (o.json) {
    std::cout << identify::session_json(result, request).dump(2) << "\n";
  } else {
    std::cout << identify::session_text(result, request, o.format);
  }
}

}  // namespace

namespace {

// What is read: the data, its units and columns, the channels, the declared model.
void add_input_options(CLI::App* cmd, IdentifyCliOptions& o) {
  cmd->add_option("data", o.data,
                  "CSV time,command,measured,force, a raw DAQ export (Header Size: ...) or a "
                  "distributed run's record RECORD.rthsrec (every link and actuator identified)")
      ->required();
  cmd->add_option("--time-unit", o.time_unit, "CSV time unit: s | ms");
  cmd->add_option("--length-unit", o.length_unit,
                  "CSV displacement unit: m | mm | cm | in (default mm; echoed in every report)");
  cmd->add_option("--force-unit", o.force_unit, "CSV force unit: N | kN | lbf | kip");
  cmd->add_option("--column-map", o.column_map,
                  "DAQ columns and scales to mm / N, e.g. "
                  "command=CHANNEL2*10,measured=CHANNEL0*10,force=CHANNEL1*9806.65 (the default)");
  cmd->add_option("--channels", o.request.channels, "channels to identify: measured,force")
      ->delimiter(',');
  cmd->add_option(
      "--model", o.model,
      "declared model file (text-format rths.config.DeclaredModel, proto/identify.proto): "
      "actuator stages, specimen kind, each parameter's initial value, min, max, fixed; "
      "replaces --declared-actuator / --declared-specimen for the channels it declares");
  cmd->add_option(
         "--sample-rate", o.sample_rate,
         "sampling rate (Hz) of a file without a time column (CSV without `time`, DAQ "
         "export without Sampling Interval/Rate); checked against the file's own when both")
      ->check(in_range(study::Quantity::kFrequency));
}

// How the candidates are searched and the held-out error judged.
void add_search_options(CLI::App* cmd, IdentifyCliOptions& o) {
  cmd->add_option("--candidates", o.request.candidates,
                  "candidate effects (default: the whole library)")
      ->delimiter(',');
  cmd->add_option("--holdout", o.request.holdout, "held-out share of the record")
      ->check(finite_in(0.01, 0.99));
  cmd->add_option("--holdout-mode", o.request.holdout_mode, "blocks (segment-wise) | last")
      ->check(CLI::IsMember({"blocks", "last"}));
  cmd->add_option("--blocks", o.request.holdout_blocks,
                  "number of segments for --holdout-mode blocks")
      ->check(CLI::Range(2, 1000));
  cmd->add_option("--min-improvement", o.request.min_improvement,
                  "relative fall of the held-out error an effect must bring")
      ->check(finite_in(0.0, 1.0));
  cmd->add_option("--penalty", o.request.penalty, "relative penalty per added parameter")
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--max-steps", o.request.max_steps, "at most this many effects per channel")
      ->check(CLI::Range(0, 1000));  // 0: fit the declared model only
  cmd->add_option("--decimate", o.request.search_decimation,
                  "decimation for the search (0: automatic)");
  cmd->add_option("--search-samples", o.request.search_samples,
                  "automatic decimation keeps at most about this many samples")
      ->check(in_range(study::Quantity::kCount));
  cmd->add_option("--search-tolerance", o.request.search_tolerance,
                  "relative change of cost or parameters at which a fit of the decimated search "
                  "stops (the full-rate refits stop at 1e-10)")
      ->check(finite_in(1e-12, 1e-2));
  cmd->add_option("--search-iterations", o.request.search_iterations,
                  "at most this many solver iterations per fit of the decimated search")
      ->check(CLI::Range(1, 1000));
}

// What is written and run with the result: plots and tables, prediction, compensator, validation.
void add_output_options(CLI::App* cmd, IdentifyCliOptions& o) {
  cmd->add_option(
      "--out", o.out,
      "directory for PNG plots with an SVG beside each (gnuplot; among them measured_bode.png, the "
      "actuator's amplitude ratio and phase, measured by Welch H1 against the models, over the "
      "band where the coherence >= 0.9), identify.<format> (the record and the declared and final "
      "models' predictions), identified_model.textproto (for --model), "
      "identified_study_fragment.textproto (study-config parts) and, with --predict, "
      "identified_study.textproto (for rths run); for a RECORD.rthsrec: identified_run.textproto "
      "(the run's study with the identified actuator as case identified_actuator and each "
      "substructure link's measured lag; rths run / launch accept it) and the lag trace of every "
      "link, lag_node_<id>.csv, with the plots record_lag.png (lag per link: measured, injected, "
      "identified model), record_response.png (response per floor: recorded, declared and "
      "identified re-runs) and record_shares.png (what each link and effect explains)");
  cmd->add_option("--format", o.format,
                  "identify.csv, identify.mat (MATLAB) or identify.h5 (HDF5) in --out")
      ->check(CLI::IsMember({"csv", "mat", "h5"}));
  cmd->add_option(
      "--predict", o.predict,
      "study config to run with the identified actuator (e.g. configs/paper_frame.textproto); "
      "with --out, also written back with the identified model as identified_study.textproto");
  cmd->add_option("--design-compensator", o.design_compensator,
                  "write a compensator designed from the identified actuator to --out: "
                  "polynomial | ats | model-based | model-based-adaptive")
      ->check(CLI::IsMember({"polynomial", "ats", "model-based", "model-based-adaptive"}));
  cmd->add_option("--design-dt", o.design_dt, "integration step of the planned test (s, or 1ms)")
      ->transform(seconds_in(study::Quantity::kStep));
  cmd->add_option("--folds", o.folds,
                  "k-fold validation over contiguous blocks of the final model (0: off)");
  cmd->add_option("--validate", o.validate,
                  "another record of the same rig: the identified models' error on it");
  cmd->add_flag(
      "--trim-idle", o.trim_idle,
      "cut the idle stretches before and after the test off the record(s): keep from "
      "0.25 s before the command first leaves its rest by 5 % of its peak to 0.25 s after "
      "it last does");
  cmd->add_flag("--json", o.json, "print the steps and models as JSON");
}

}  // namespace

void add_identify_command(CLI::App& app) {
  auto o = std::make_shared<IdentifyCliOptions>();
  CLI::App* cmd = app.add_subcommand(
      "identify", "Find the effects a declared actuator/specimen model lacks in measured data");
  add_input_options(cmd, *o);
  CLI::Option* actuator_flag =
      cmd->add_option("--declared-actuator", o->request.declared_actuator,
                      "declared actuator effects (gain is always there), comma list or none")
          ->delimiter(',');
  CLI::Option* specimen_flag = cmd->add_option("--declared-specimen", o->request.declared_specimen,
                                               "declared specimen effects, comma list or none")
                                   ->delimiter(',');
  add_search_options(cmd, *o);
  add_output_options(cmd, *o);
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
