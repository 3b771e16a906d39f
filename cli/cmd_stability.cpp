// `rths stability`: the critical delay of a delayed SDOF hybrid system, continuous and discrete;
// with --study/--case, the delay margin of that case's actuator and compensator in the loop (a
// study of several DOFs: the verdict `rths run` gives before the run, by the modal
// approximation, stated as such; a case with a force predictor, on any structure: the coupled
// loop of every link with its predictor, each link's critical lag, core::setup_loop_stability).
#include <nlohmann/json.hpp>

#include <cmath>
#include <iostream>
#include <memory>
#include <numbers>
#include <optional>
#include <sstream>

#include "analysis/study_run/study_run.h"
#include "cli/commands.h"
#include "cli/support.h"
#include "core/stability.h"
#include "study/stability_config.h"
#include "study/study.h"

namespace rths::cli {
namespace {

struct StabilityOptions {
  double period = 0.5, zeta = 0.05, alpha = 1.0, dt = 0.001;
  std::string integrator = "explicit-newmark";
  int branches = 3, max_steps = 200;
  bool json = false;
  std::string study, case_name;
  double max_extra_delay = 0.1;
  // A Smith predictor on the force whose model is off by these (core::predictor_critical_delay):
  // stiffness as a fraction of the specimen's (-0.3: 30 % soft), damping as a fraction of the
  // critical 2 m omega_n. Unset: no predictor.
  std::optional<double> predictor_stiffness_error, predictor_damping_error;
  bool predicted() const { return predictor_stiffness_error || predictor_damping_error; }
};

// The compensated loop of the SDOF options, when a predictor is asked for.
std::optional<core::ContinuousStability> predictor_stability(const StabilityOptions& o) {
  if (!o.predicted()) return std::nullopt;
  return core::predictor_critical_delay(o.period, o.zeta, o.alpha,
                                        o.predictor_stiffness_error.value_or(0.0),
                                        o.predictor_damping_error.value_or(0.0), o.branches);
}

std::string predictor_text(const StabilityOptions& o, const core::ContinuousStability& p) {
  std::ostringstream out;
  out.precision(4);
  out << "with a force predictor whose model's stiffness is " << std::showpos
      << 100.0 * o.predictor_stiffness_error.value_or(0.0) << " %" << std::noshowpos
      << " and damping " << 100.0 * o.predictor_damping_error.value_or(0.0)
      << " % of critical off the specimen's (frozen): ";
  if (p.critical_delay)
    out << "critical lag of the measured pair (round trip + actuator) = " << *p.critical_delay * 1e3
        << " ms";
  else
    out << "stable at every lag";
  return out.str();
}

// The SDOF loop of a study case: period, zeta, alpha, dt and integrator from the config, the
// case's delay stages as the actuator and its compensation (at most one block: one actuator).
struct CompensatedLoop {
  double period = 0, zeta = 0, alpha = 0, dt = 0;
  core::IntegratorKind kind{};
  const config::Case* chosen = nullptr;
  const config::Compensation* compensation = nullptr;
};

CompensatedLoop compensated_loop_of(const config::Study& study, const StabilityOptions& o) {
  const auto& s = study.structure();
  if (!s.has_sdof())
    throw std::invalid_argument(o.study +
                                ": --study needs structure.sdof (the analysis is of an SDOF loop)");
  if (s.damping().has_rayleigh())
    throw std::invalid_argument(o.study + ": --study needs structure.damping.modal_zeta");
  CompensatedLoop loop;
  const core::StructuralModel model = study::make_structure(s);
  loop.period = 2.0 * std::numbers::pi * std::sqrt(model.mass(0, 0) / model.stiffness(0, 0));
  loop.zeta = s.damping().modal_zeta();
  loop.alpha = study.substructuring().experimental_fraction();
  if (!study.substructuring().experimental_storeys().empty())
    throw std::invalid_argument(o.study + ": --study needs substructuring.experimental_fraction");
  loop.dt = study.integrator().dt();
  if (!(loop.dt > 0)) throw std::invalid_argument(o.study + ": --study needs integrator.dt > 0");
  loop.kind = study::integrator_kind(study.integrator());
  for (const auto& c : study.cases())
    if (c.name() == o.case_name) loop.chosen = &c;
  if (!loop.chosen)
    throw std::invalid_argument(o.study + ": --case '" + o.case_name + "' is not among the cases");
  if (loop.chosen->compensation_size() > 1)
    throw std::invalid_argument("--case '" + o.case_name +
                                "': one compensation block expected (an SDOF has one actuator)");
  if (loop.chosen->compensation_size() == 1) loop.compensation = &loop.chosen->compensation(0);
  return loop;
}

nlohmann::json compensated_json(const StabilityOptions& o, const CompensatedLoop& loop,
                                const core::CompensatedStability& r) {
  const auto optional = [](const std::optional<double>& v) {
    return v ? nlohmann::json(*v) : nlohmann::json();
  };
  nlohmann::json out;
  out["input"] = {{"study", o.study},
                  {"case", o.case_name},
                  {"period_s", loop.period},
                  {"zeta", loop.zeta},
                  {"experimental_fraction", loop.alpha},
                  {"integrator", core::to_string(loop.kind)},
                  {"dt_s", loop.dt},
                  {"compensated", loop.compensation != nullptr}};
  if (!r.frozen_coefficients.empty())
    out["time_varying"] = {{"analysis", "frozen coefficients"}, {"note", r.frozen_coefficients}};
  if (!r.linearised.empty()) out["linearised"] = r.linearised;
  nlohmann::json crossings = nlohmann::json::array();
  for (const auto& c : r.crossings)
    crossings.push_back(
        {{"crossing_omega_rad_per_s", c.omega}, {"extra_delay_s", c.delay}, {"branch", c.branch}});
  out["discrete"] = {{"stable", r.stable},
                     {"spectral_radius", r.spectral_radius},
                     {"extra_delay_margin_s", optional(r.discrete_margin)},
                     {"searched_up_to_s", r.max_extra_delay}};
  out["continuous"] = {{"extra_delay_margin_s", optional(r.continuous_margin)},
                       {"crossings", crossings}};
  return out;
}

void print_compensated(const StabilityOptions& o, const CompensatedLoop& loop,
                       const core::CompensatedStability& r) {
  std::cout << "case '" << o.case_name << "' of " << o.study << ": SDOF T = " << loop.period
            << " s, zeta = " << loop.zeta << ", alpha = " << loop.alpha << ", "
            << core::to_string(loop.kind) << " dt = " << loop.dt * 1e3 << " ms, "
            << (loop.compensation ? "compensated" : "uncompensated") << "\n";
  if (!r.frozen_coefficients.empty()) {
    std::cout << "compensator is " << r.frozen_coefficients
              << "; no fixed amplification matrix exists for the adapting loop, so the figures "
                 "below are of the frozen loop\n";
  }
  if (!r.linearised.empty()) std::cout << "linearised: " << r.linearised << "\n";
  if (!r.stable) {
    std::cout << "discrete: UNSTABLE as configured (spectral radius " << r.spectral_radius << ")\n";
  } else if (r.discrete_margin) {
    std::cout << "discrete: stable; it tolerates " << *r.discrete_margin * 1e3
              << " ms of extra delay\n";
  } else {
    std::cout << "discrete: stable up to " << r.max_extra_delay * 1e3 << " ms of extra delay\n";
  }
  if (r.continuous_margin) {
    std::cout << "continuous: first crossing at " << *r.continuous_margin * 1e3
              << " ms of extra delay (omega = " << r.crossings.front().omega << " rad/s)\n";
  } else {
    std::cout << "continuous: no crossing (|k_e H| stays below the numerical part at every "
                 "frequency)\n";
  }
}

// A study of several DOFs (matrices, a shear building), or a case with a force predictor on any
// structure: the verdict `rths run` gives the case before it runs it (analysis::pre_run_verdict): a
// compensator's loop by the modal approximation, a force predictor's by the coupled loop of its
// links, each stated as such.
// Exit 1 when the compensated loop is analysed unstable.
void run_modal(const StabilityOptions& o, const config::Study& study) {
  const std::filesystem::path path = o.study;
  const study::PreparedStudy prepared = study::prepare_study(study, path.parent_path());
  const analysis::CaseOutcome c = analysis::pre_run_verdict(prepared, o.case_name);
  analysis::StudyOutcome alone;
  alone.study_name = study.name();
  alone.cases = {c};
  const nlohmann::json summary = analysis::study_summary_json(alone)["cases"][0];
  if (o.json) {
    std::cout << nlohmann::json{{"input",
                                 {{"study", o.study},
                                  {"case", o.case_name},
                                  {"dofs", prepared.base.model.dofs()},
                                  {"compensated", c.compensated.has_value()}}},
                                {"stability", summary["stability"]},
                                {"compensated_loop", summary["compensated_loop"]}}
                     .dump(2)
              << "\n";
  } else {
    std::cout << "case '" << o.case_name << "' of " << o.study << ": " << prepared.base.model.dofs()
              << " DOFs\n";
    // A compensated case's own check counts its compensator's lead; its verdict names the
    // uncompensated lag's check instead.
    if (c.stability && !c.compensated) std::cout << c.stability->describe() << "\n";
    if (c.stability) std::cout << "assumed: " << c.stability->assumed << "\n";
    if (c.compensated) std::cout << c.compensated->text << "\n";
  }
  if (c.compensated && c.compensated->analysed && !c.compensated->stable)
    throw ExitError(kExitRunFailed,
                    "the loop of case '" + o.case_name + "' is unstable as configured");
  if (!c.compensated && c.stability && c.stability->past())
    throw ExitError(kExitRunFailed, "case '" + o.case_name +
                                        "' is past its critical delay: " + c.stability->describe());
}

// Whether --case names a case with a force predictor: its verdict is the coupled loop's, on any
// structure (run_modal), not the SDOF actuator-and-compensator loop's.
bool predicted_case(const config::Study& study, const std::string& name) {
  for (const auto& c : study.cases())
    if (c.name() == name && c.has_force_predictor()) return true;
  return false;
}

void run_compensated(const StabilityOptions& o) {
  const config::Study study = study::load_study(o.study);
  if (!study.structure().has_sdof() || predicted_case(study, o.case_name)) {
    run_modal(o, study);
    return;
  }
  const CompensatedLoop loop = compensated_loop_of(study, o);
  const core::CompensatedStability r = study::compensated_stability(
      loop.kind, loop.period, loop.zeta, loop.alpha, loop.dt, loop.chosen->delay(),
      loop.compensation, o.max_extra_delay, o.branches);
  if (o.json)
    std::cout << compensated_json(o, loop, r).dump(2) << "\n";
  else
    print_compensated(o, loop, r);
  if (!r.stable)
    throw ExitError(kExitRunFailed,
                    "the loop of case '" + o.case_name + "' is unstable as configured");
}

nlohmann::json sdof_stability_json(const StabilityOptions& o, core::IntegratorKind kind,
                                   const core::ContinuousStability& continuous,
                                   const core::DiscreteStability& discrete,
                                   const std::optional<core::ContinuousStability>& predicted) {
  nlohmann::json out;
  out["input"] = {{"period_s", o.period},
                  {"zeta", o.zeta},
                  {"experimental_fraction", o.alpha},
                  {"integrator", core::to_string(kind)},
                  {"dt_s", o.dt}};
  nlohmann::json crossings = nlohmann::json::array();
  for (const auto& c : continuous.crossings) {
    crossings.push_back(
        {{"crossing_omega_rad_per_s", c.omega}, {"delay_s", c.delay}, {"branch", c.branch}});
  }
  out["continuous"] = {
      {"stable_without_delay", continuous.stable_without_delay},
      {"stable_for_all_delays", continuous.stable_for_all_delays},
      {"critical_delay_s",
       continuous.critical_delay ? nlohmann::json(*continuous.critical_delay) : nlohmann::json()},
      {"crossings", crossings}};
  out["discrete"] = {
      {"first_unstable_delay_steps", discrete.first_unstable_steps
                                         ? nlohmann::json(*discrete.first_unstable_steps)
                                         : nlohmann::json()},
      {"first_unstable_delay_s", discrete.first_unstable_delay
                                     ? nlohmann::json(*discrete.first_unstable_delay)
                                     : nlohmann::json()},
      {"searched_up_to_steps", o.max_steps},
      {"spectral_radius_at_first_unstable", discrete.spectral_radius.empty()
                                                ? nlohmann::json()
                                                : nlohmann::json(discrete.spectral_radius.back())}};
  if (predicted)
    out["predictor"] = {
        {"stiffness_error", o.predictor_stiffness_error.value_or(0.0)},
        {"damping_error", o.predictor_damping_error.value_or(0.0)},
        {"stable_for_all_delays", !predicted->critical_delay.has_value()},
        {"critical_delay_s",
         predicted->critical_delay ? nlohmann::json(*predicted->critical_delay) : nlohmann::json()},
        {"text", predictor_text(o, *predicted)}};
  return out;
}

void print_sdof_stability(const StabilityOptions& o, core::IntegratorKind kind,
                          const core::ContinuousStability& continuous,
                          const core::DiscreteStability& discrete) {
  std::cout << "SDOF T = " << o.period << " s, zeta = " << o.zeta
            << ", experimental fraction = " << o.alpha << "\n";
  if (continuous.stable_for_all_delays) {
    std::cout << "continuous: stable for every delay (|k_e| too small to cross)\n";
  } else if (continuous.critical_delay) {
    std::cout << "continuous: critical delay = " << *continuous.critical_delay * 1e3 << " ms\n";
    for (const auto& c : continuous.crossings) {
      std::cout << "  crossing at omega = " << c.omega << " rad/s, branch " << c.branch
                << ": delay = " << c.delay * 1e3 << " ms\n";
    }
  }
  if (discrete.first_unstable_steps) {
    std::cout << core::to_string(kind) << ", dt = " << o.dt * 1e3
              << " ms: first unstable delay = " << *discrete.first_unstable_steps << " steps ("
              << *discrete.first_unstable_delay * 1e3 << " ms), spectral radius "
              << discrete.spectral_radius.back() << "\n";
  } else {
    std::cout << core::to_string(kind) << ", dt = " << o.dt * 1e3 << " ms: stable up to "
              << o.max_steps << " steps of delay\n";
  }
}

void run_stability(const StabilityOptions& o) {
  if (!o.study.empty()) {
    run_compensated(o);
    return;
  }
  const auto kind = core::integrator_from_string(o.integrator);
  // Beyond the integrator's own limit every delay is unstable, so "first unstable delay = 0
  // steps" would answer the wrong question: refuse the input instead.
  core::check_stability(kind, 2.0 * std::numbers::pi / o.period, o.dt, false);
  const core::ContinuousStability continuous =
      core::continuous_critical_delay(o.period, o.zeta, o.alpha, o.branches);
  const core::DiscreteStability discrete =
      core::discrete_critical_delay(kind, o.period, o.zeta, o.alpha, o.dt, o.max_steps);
  const std::optional<core::ContinuousStability> predicted = predictor_stability(o);
  if (o.json) {
    std::cout << sdof_stability_json(o, kind, continuous, discrete, predicted).dump(2) << "\n";
    return;
  }
  print_sdof_stability(o, kind, continuous, discrete);
  if (predicted) std::cout << predictor_text(o, *predicted) << "\n";
}

}  // namespace

void add_stability_command(CLI::App& app) {
  auto options = std::make_shared<StabilityOptions>();
  CLI::App* cmd = app.add_subcommand("stability", "Critical delay of a delayed SDOF hybrid system");
  cmd->add_option("--period", options->period, "natural period T (s, or 500ms)")
      ->transform(seconds_in(study::Quantity::kPeriod));
  cmd->add_option("--zeta", options->zeta, "damping ratio")
      ->check(in_range(study::Quantity::kDampingRatio));
  cmd->add_option("--exp-fraction", options->alpha, "experimental fraction alpha of the stiffness")
      ->check(in_range(study::Quantity::kFraction));
  cmd->add_option("--dt", options->dt,
                  "integration step (s, or 1ms); exit 2 beyond the integrator's limit")
      ->transform(seconds_in(study::Quantity::kStep));
  cmd->add_option(
      "--integrator", options->integrator,
      "explicit-newmark | central-difference | chen-ricles | newmark-average-acceleration");
  cmd->add_option("--branches", options->branches, "delay branches listed per crossing frequency")
      ->check(CLI::Range(1, 100));
  cmd->add_option("--max-steps", options->max_steps, "largest delay (steps) searched")
      ->check(CLI::Range(0, 5000));
  cmd->add_option(
      "--study", options->study,
      "study config: analyse the loop of --case, its actuator stages and compensation (an SDOF "
      "exactly; several DOFs by the modal approximation; a force predictor on any structure by "
      "the coupled loop of its links; as `rths run` judges it before the run)");
  cmd->add_option("--case", options->case_name,
                  "case of --study whose actuator and compensator are analysed");
  cmd->add_option("--max-extra-delay", options->max_extra_delay,
                  "largest extra delay searched with --study (s)")
      ->transform(seconds_in(study::Quantity::kLag));
  cmd->add_option("--predictor-stiffness-error", options->predictor_stiffness_error,
                  "with a force predictor whose model's stiffness is off by this fraction of the "
                  "specimen's (-0.3: 30 % soft): its loop's critical lag")
      ->check(finite_in(-0.99, 10.0));
  cmd->add_option(
         "--predictor-damping-error", options->predictor_damping_error,
         "the predictor model's damping error, a fraction of the critical damping (>= 0: the "
         "specimen's own damping is taken as 0, so it is the model's damping ratio)")
      ->check(finite_in(0.0, 10.0));
  cmd->add_flag("--json", options->json, "print JSON");
  cmd->callback([options] {
    if (options->study.empty() != options->case_name.empty()) {
      throw std::invalid_argument("--study and --case go together");
    }
    if (!options->study.empty() && options->predicted())
      throw std::invalid_argument(
          "--predictor-stiffness-error and --predictor-damping-error are for the SDOF loop "
          "(--period ...); a study's case states its own predictor's verdict (rths run)");
    run_stability(*options);
  });
}

}  // namespace rths::cli
