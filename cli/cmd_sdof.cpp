// `rths sdof`: one SDOF run from flags alone: the reference (no delay) against one delay model.
// The flags are turned into a study config, so `rths sdof` and `rths run` share one code path.
#include <nlohmann/json.hpp>

#include <filesystem>
#include <iostream>
#include <map>
#include <memory>

#include "analysis/study_run/study_run.h"
#include "analysis/tables/result_tables.h"
#include "cli/commands.h"
#include "cli/support.h"
#include "results/results.h"
#include "results/write.h"
#include "study/study.h"
#include "util/atomic_file.h"
#include "util/distinct_paths.h"

namespace rths::cli {
namespace {

struct SdofOptions {
  double period = 0.5, zeta = 0.05, dt = 0.0, motion_dt = 0.0, delay = 0.0, alpha = 1.0,
         scale = 1.0;
  std::string motion, motion_units, delay_model = "shift", integrator = "explicit-newmark", out;
  bool json = false, allow_unstable = false;
};

config::Study study_from_flags(const SdofOptions& o) {
  config::Study study;
  study.set_name("sdof");
  study.mutable_structure()->mutable_sdof()->set_period(o.period);
  study.mutable_structure()->mutable_damping()->set_modal_zeta(o.zeta);
  study.mutable_motion()->set_path(o.motion);
  study.mutable_motion()->set_scale(o.scale);
  study.mutable_motion()->set_column_dt(o.motion_dt);
  if (!o.motion_units.empty())
    study.mutable_motion()->set_column_units(study::units_from_name(o.motion_units));
  study.mutable_integrator()->set_dt(o.dt);
  study.mutable_integrator()->set_allow_unstable(o.allow_unstable);
  study.mutable_integrator()->set_kind(
      study::config_integrator_kind(core::integrator_from_string(o.integrator)));
  study.mutable_substructuring()->set_experimental_fraction(o.alpha);
  study.add_cases()->set_name("reference");
  config::Case* delayed = study.add_cases();
  delayed->set_name("delayed");
  if (o.delay_model != "none") {
    config::DelayStage* stage = delayed->add_delay();
    if (o.delay_model == "shift")
      stage->mutable_shift()->set_delay(o.delay);
    else if (o.delay_model == "eq1")
      stage->mutable_eq1()->set_delay(o.delay);
    else if (o.delay_model == "eq1-lag")
      stage->mutable_eq1_lag()->set_delay(o.delay);
    else if (o.delay_model == "first-order")
      stage->mutable_first_order()->set_time_constant(o.delay);
    else if (o.delay_model == "benchmark")
      stage->mutable_benchmark();
    else
      throw std::invalid_argument("unknown --delay-model '" + o.delay_model + "'");
  }
  study::validate_study(study, "command line");
  return study;
}

void run_sdof(const SdofOptions& o) {
  if (o.delay_model == "first-order" && !(o.delay > 0)) {
    throw std::invalid_argument(
        "--delay-model first-order needs --delay > 0 (its time constant, s)");
  }
  util::refuse_output_over_input({"--out", o.out}, {{"--motion", o.motion}});
  const config::Study study = study_from_flags(o);
  const study::PreparedStudy prepared =
      study::prepare_study(study, std::filesystem::current_path());
  const analysis::StudyOutcome outcome = analysis::run_study(prepared, {.warn = print_warning});
  const analysis::CaseOutcome& reference = outcome.cases[0];
  const analysis::CaseOutcome& delayed = outcome.cases[1];
  if (!o.out.empty())
    results::write_table(analysis::study_table(outcome), o.out, results::Format::kCsv);
  if (o.json) {
    nlohmann::json out = {{"period_s", o.period},
                          {"zeta", o.zeta},
                          {"experimental_fraction", o.alpha},
                          {"dt_s", prepared.base.dt},
                          {"motion_units", outcome.motion_units},
                          {"motion", outcome.motion_description},
                          {"delay_model", o.delay_model},
                          {"delay_s", o.delay},
                          {"integrator", o.integrator},
                          {"peak_reference_m", reference.comparison.peak_m},
                          {"peak_delayed_m", delayed.comparison.peak_m},
                          {"peak_error_pct", delayed.comparison.peak_error_pct},
                          {"rms_error_pct", delayed.comparison.rms_error_pct},
                          {"paper_eq2_as_printed", delayed.comparison.paper_eq2_as_printed},
                          {"nrmse_pct", delayed.comparison.nrmse_pct},
                          {"peak_error_m", delayed.comparison.peak_error_m},
                          {"status", delayed.status},
                          {"status_detail", delayed.status_detail},
                          {"diverged", delayed.diverged()}};
    const nlohmann::json cases = analysis::study_summary_json(outcome)["cases"];
    out["stability"] = cases[1]["stability"];
    out["envelope_growth"] = cases[1]["envelope_growth"];
    out["measures"] = analysis::error_measures_json();
    std::cout << out.dump(2) << "\n";
  } else {
    std::cout << analysis::study_summary_text(outcome);
  }
  fail_if_unstable(outcome, o.allow_unstable);
}

}  // namespace

void add_sdof_command(CLI::App& app) {
  auto o = std::make_shared<SdofOptions>();
  CLI::App* cmd = app.add_subcommand("sdof", "One SDOF run from flags: reference vs delayed");
  cmd->add_option("--period", o->period, "natural period (s)")
      ->transform(seconds_in(study::Quantity::kPeriod));
  cmd->add_option("--zeta", o->zeta, "damping ratio, 0.05 = 5 % (at most 1)")
      ->check(in_range(study::Quantity::kDampingRatio));
  cmd->add_option("--motion", o->motion, "ground motion file (PEER AT2 or columns)")->required();
  cmd->add_option("--motion-units", o->motion_units,
                  "units of the motion record: g | m/s2 | cm/s2 | in/s2 | mm/s2 (required for a "
                  "columns file; an AT2 file is read in its header's units)")
      ->check(CLI::IsMember({"g", "m/s2", "cm/s2", "in/s2", "mm/s2"}));
  cmd->add_option("--scale", o->scale, "scale factor on the motion")
      ->check(in_range(study::Quantity::kMotionScale));
  cmd->add_option("--motion-dt", o->motion_dt,
                  "sample step of a one-column motion file (s, or 5ms)")
      ->transform(seconds_in(study::Quantity::kStep));
  cmd->add_option("--dt", o->dt, "integration step (s, or 1ms); default: the record's step")
      ->transform(seconds_in(study::Quantity::kStep));
  cmd->add_option("--delay", o->delay,
                  "delay (s, or with a unit: 14ms), or the time constant for first-order")
      ->transform(seconds_in(study::Quantity::kLag));
  cmd->add_option("--delay-model", o->delay_model,
                  "none | shift | eq1 | eq1-lag | first-order | benchmark")
      ->check(CLI::IsMember({"none", "shift", "eq1", "eq1-lag", "first-order", "benchmark"}));
  cmd->add_option("--exp-fraction", o->alpha, "experimental fraction alpha of the stiffness")
      ->check(in_range(study::Quantity::kFraction));
  cmd->add_option(
      "--integrator", o->integrator,
      "explicit-newmark | central-difference | chen-ricles | newmark-average-acceleration");
  cmd->add_flag(
      "--allow-unstable", o->allow_unstable,
      "run even if dt exceeds the integrator's limit, and a diverged case does not fail the run");
  cmd->add_option("--out", o->out,
                  "CSV of both runs (results.csv columns: every floor and actuator, SI)");
  cmd->add_flag("--json", o->json,
                "print peaks, E_peak and E_rms (%), the paper's NRMSE (%) and Eq. 2, status and "
                "the critical delay as JSON");
  cmd->callback([o] { run_sdof(*o); });
}

}  // namespace rths::cli
