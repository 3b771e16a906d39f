#include "analysis/study_run/study_run.h"

#include "analysis/study_run/case_setups.h"
#include "analysis/study_run/predicted_loop.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <exception>
#include <future>
#include <iomanip>
#include <numbers>
#include <span>
#include <sstream>
#include <tuple>

#include "core/coupled_stability.h"
#include "core/metrics.h"
#include "core/sparse_structure.h"
#include "study/case_link.h"
#include "study/motion_key.h"
#include "study/stability_config.h"
#include "util/atomic_file.h"
#include "util/sha256.h"

namespace rths::analysis {
namespace {

// The first step at which |u| or |v| of a floor passed a limit (0 = no limit), with why, judged
// on each step's peaks over every DOF (core::SimulationResult), which name the floor.
std::optional<std::pair<std::size_t, std::string>> first_limit_trip(
    const core::SimulationResult& r, const config::SafetyLimits& limits) {
  for (std::size_t k = 0; k < r.steps() && k < r.peak_displacement.size(); ++k) {
    std::ostringstream why;
    why << std::setprecision(4);
    if (limits.max_displacement() > 0 && !(r.peak_displacement[k] <= limits.max_displacement())) {
      why << "|u| of floor " << r.peak_displacement_dof[k] + 1 << " = " << r.peak_displacement[k]
          << " m > limit " << limits.max_displacement() << " m at t = " << r.time[k] << " s";
      return std::make_pair(k, why.str());
    }
    if (limits.max_velocity() > 0 && !(r.peak_velocity[k] <= limits.max_velocity())) {
      why << "|v| of floor " << r.peak_velocity_dof[k] + 1 << " = " << r.peak_velocity[k]
          << " m/s > limit " << limits.max_velocity() << " m/s at t = " << r.time[k] << " s";
      return std::make_pair(k, why.str());
    }
  }
  return std::nullopt;
}

// Whether a case's setup is the base's: it sets nothing but its name and expect_unstable (no
// delay stage, compensation, predictor or link, nor any field added later).
bool adds_nothing(const config::Case& study_case) {
  config::Case rest = study_case;
  rest.clear_name();
  rest.clear_expect_unstable();
  return rest.ByteSizeLong() == 0;
}

}  // namespace

std::vector<std::string> StudyOutcome::failures(bool allow_unstable) const {
  std::vector<std::string> out;
  for (const CaseOutcome& c : cases) {
    if (c.status == "limit tripped")
      out.push_back("case '" + c.name + "': limit tripped: " + c.status_detail);
    if (c.status == "held") out.push_back("case '" + c.name + "': held: " + c.status_detail);
    if (c.diverged() && !c.expect_unstable && !allow_unstable) {
      out.push_back("case '" + c.name +
                    (c.status == "diverging" ? "' is diverging: " : "' diverged: ") +
                    c.status_detail);
    }
  }
  return out;
}

namespace {

// One mode of the structure taken as an SDOF for the compensated loop's analysis.
struct ModalSdof {
  int mode = 1;         // 1-based
  double period = 0.0;  // s
  double zeta = 0.0;    // modal damping ratio
  double alpha = 0.0;   // experimental fraction phi' K_e phi / omega^2
};

// The SDOFs the compensated loop is analysed on: the structure itself when it has one DOF
// (exact), else every mode of (M, K) that carries experimental stiffness (the modal
// approximation, as core::check_modal_critical_delay takes it).
std::vector<ModalSdof> loop_sdofs(const core::HybridSetup& setup, const core::Mat& k_experimental,
                                  double sdof_alpha) {
  const core::StructuralModel& model = setup.model;
  if (model.dofs() == 1) {
    const double m = model.mass(0, 0), k = model.stiffness(0, 0), c = model.damping(0, 0);
    const double omega = std::sqrt(k / m);
    return {{1, 2.0 * std::numbers::pi / omega, c / (2.0 * m * omega), sdof_alpha}};
  }
  // A model held sparse: its lowest modes, as core::check_modal_critical_delay takes them.
  const int count = model.is_sparse() ? std::min(20, model.dofs() - 1) : model.dofs();
  const core::Modes modes = core::lowest_modes(model, count);
  std::vector<ModalSdof> out;
  for (int i = 0; i < count; ++i) {
    const double omega = modes.omega[i];
    const core::Vec phi = modes.shapes.col(i);
    const double alpha = std::clamp(phi.dot(k_experimental * phi) / (omega * omega), 0.0, 1.0);
    if (!(alpha > 0.0)) continue;
    out.push_back({i + 1, 2.0 * std::numbers::pi / omega,
                   core::damping_quadratic(model, phi) / (2.0 * omega), alpha});
  }
  return out;
}

// The compensated loop of each modal SDOF, gathered: whether every mode is stable, the first
// unstable one, and the smallest extra delay tolerated with the mode that governs it.
struct ModalLoops {
  bool stable = true, unbounded = true;  // unbounded: every mode stable up to the searched range
  bool adaptive = false;                 // frozen coefficients: not judged before the run
  double radius = 0.0;
  int unstable_mode = 0, governing = 0;
  std::optional<double> margin;
  std::string linearised;
};

ModalLoops analyse_modal_loops(const core::HybridSetup& setup, const config::Case& study_case,
                               const std::vector<ModalSdof>& sdofs, double max_extra_delay) {
  ModalLoops m;
  for (const ModalSdof& sdof : sdofs) {
    const core::CompensatedStability loop = study::compensated_stability(
        setup.integrator, sdof.period, sdof.zeta, sdof.alpha, setup.dt, study_case.delay(),
        &study_case.compensation(0), max_extra_delay);
    if (!loop.frozen_coefficients.empty()) {
      m.adaptive = true;
      return m;
    }
    if (!loop.linearised.empty()) m.linearised = loop.linearised;
    if (!loop.stable) {
      if (m.stable) {
        m.radius = loop.spectral_radius;
        m.unstable_mode = sdof.mode;
      }
      m.stable = false;
      continue;
    }
    std::optional<double> mode_margin = loop.continuous_margin;
    if (loop.discrete_margin)
      mode_margin =
          mode_margin ? std::min(*mode_margin, *loop.discrete_margin) : loop.discrete_margin;
    if (mode_margin) {
      m.unbounded = false;
      if (!m.margin || *mode_margin < *m.margin) {
        m.margin = mode_margin;
        m.governing = sdof.mode;
      }
    }
  }
  return m;
}

std::string modal_loops_text(const ModalLoops& m, bool modal, std::size_t modes,
                             double max_extra_delay) {
  std::ostringstream text;
  text << std::setprecision(3) << "compensated loop: ";
  if (!m.stable) {
    text << "UNSTABLE as configured (spectral radius " << m.radius;
    if (modal) text << ", mode " << m.unstable_mode;
    text << ")";
  } else if (m.margin && !m.unbounded) {
    text << "stable, tolerates " << *m.margin * 1e3 << " ms more lag";
    if (modal) text << " (mode " << m.governing << " governs)";
  } else {
    text << "stable for up to " << max_extra_delay * 1e3 << " ms more lag (searched)";
  }
  if (modal)
    text << " (modal approximation over the " << modes
         << " modes with experimental stiffness, each an SDOF; the coupling the delayed force "
            "adds between modes is ignored)";
  if (!m.linearised.empty()) text << " (linearised: " << m.linearised << ")";
  return text.str();
}

// The compensated loop of a case with one compensator (CompensatedVerdict): exact for one storey,
// the modal approximation (each mode with experimental stiffness an SDOF, the smallest margin
// kept, stated as such) for several. None for a case without compensation or experimental part.
std::optional<CompensatedVerdict> judge_compensated_loop(
    const core::HybridSetup& setup, const core::Mat& k_experimental, const config::Case& study_case,
    const std::optional<core::CriticalDelayCheck>& uncompensated) {
  constexpr double kMaxExtraDelay = 0.1;  // s searched beyond the configured loop
  if (study_case.compensation_size() == 0 || !uncompensated) return std::nullopt;
  CompensatedVerdict verdict;
  const std::string beside = "; uncompensated, " + uncompensated->describe();
  if (study_case.compensation_size() != 1) {
    verdict.text =
        "the compensated loop is analysed for one compensator only (one actuator): not judged "
        "before the run" +
        beside;
    return verdict;
  }
  const std::vector<ModalSdof> sdofs =
      loop_sdofs(setup, k_experimental, uncompensated->governing_fraction);
  try {
    const ModalLoops m = analyse_modal_loops(setup, study_case, sdofs, kMaxExtraDelay);
    if (m.adaptive) {
      verdict.text =
          "adaptive compensation: its coefficients change during the run, so its loop cannot "
          "be judged before it" +
          beside;
      return verdict;
    }
    verdict.analysed = true;
    verdict.stable = m.stable;
    if (m.stable) verdict.extra_delay_tolerated = m.margin;
    verdict.text =
        modal_loops_text(m, setup.model.dofs() > 1, sdofs.size(), kMaxExtraDelay) + beside;
  } catch (const std::invalid_argument& e) {
    verdict.text =
        std::string("the compensated loop cannot be analysed (") + e.what() + ")" + beside;
  }
  return verdict;
}

// The pre-run warning of a case, if any: the compensated loop's verdict when the case has
// compensation, else the uncompensated lag past its critical delay.
std::optional<std::string> pre_run_warning(const CaseOutcome& c) {
  const std::string meant =
      c.expect_unstable ? " (expect_unstable: meant)" : "; expect it to diverge";
  if (c.compensated) {
    if (c.compensated->analysed && !c.compensated->stable) return c.compensated->text + meant;
    if (!c.compensated->analysed && c.stability && c.stability->past()) return c.compensated->text;
    return std::nullopt;
  }
  if (c.stability && c.stability->past()) return c.stability->describe() + meant;
  return std::nullopt;
}

// Whether two loops' parts are the same specimens at the same places (their lags aside).
bool same_parts(const std::vector<core::DelayedPart>& a, const std::vector<core::DelayedPart>& b) {
  if (a.size() != b.size()) return false;
  for (std::size_t j = 0; j < a.size(); ++j) {
    const core::DelayedPart &p = a[j], &q = b[j];
    if (p.row.size() != q.row.size() || p.row != q.row || p.stiffness != q.stiffness ||
        p.damping != q.damping || p.mass != q.mass || p.predicted != q.predicted ||
        p.model_stiffness != q.model_stiffness || p.model_damping != q.model_damping)
      return false;
  }
  return true;
}

// Cases whose loops are the same share one critical-delay check, made at the largest of their
// lags (its discrete search reaches every smaller lag's), each case's copy at its own lag. Asked
// in case order (for_case: case i's, on its setup), so a loop is checked on its first case's.
class SharedChecks {
 public:
  explicit SharedChecks(const std::vector<CaseLoop>& cases) {
    for (const CaseLoop& c : cases) {
      auto same = std::find_if(loops_.begin(), loops_.end(),
                               [&](const Loop& l) { return same_parts(l.parts, c.parts); });
      if (same == loops_.end())
        same = loops_.insert(loops_.end(), Loop{c.parts, c.lag, std::nullopt, false});
      same->lag = std::max(same->lag, c.lag);
      loop_of_.push_back(static_cast<std::size_t>(same - loops_.begin()));
      lag_of_.push_back(c.lag);
    }
  }
  std::optional<core::CriticalDelayCheck> for_case(const study::PreparedStudy& prepared,
                                                   std::size_t i, const core::HybridSetup& setup) {
    Loop& loop = loops_[loop_of_[i]];
    if (!loop.checked) {
      loop.check = study::check_setup_critical_delay(prepared, setup, loop.lag);
      loop.checked = true;
    }
    std::optional<core::CriticalDelayCheck> check = loop.check;
    if (check) check->lag = lag_of_[i];
    return check;
  }

 private:
  struct Loop {
    std::vector<core::DelayedPart> parts;
    double lag = 0.0;  // s, the largest of its cases'
    std::optional<core::CriticalDelayCheck> check;
    bool checked = false;
  };
  std::vector<Loop> loops_;
  std::vector<std::size_t> loop_of_;
  std::vector<double> lag_of_;  // s
};

// What is known of a case before it runs: its delay, and its critical-delay check (announced
// through options.warn when past; for a compensated case, its compensated loop's verdict).
// `check`: the case's critical-delay check at its lag (shared_checks).
CaseOutcome describe_case(const study::PreparedStudy& prepared, const core::HybridSetup& setup,
                          const config::Case& study_case, const std::string& name,
                          const RunStudyOptions& options,
                          std::optional<core::CriticalDelayCheck> check) {
  CaseOutcome result;
  result.name = name;
  result.expect_unstable = study_case.expect_unstable();
  result.nominal_delay = study::answer_lag(setup);
  result.delay_description = study::case_delay_text(setup);
  result.stability = std::move(check);
  if (study_case.compensation_size() > 0) {
    // Beside the compensated loop's verdict: the same case without its compensators.
    config::Case bare = study_case;
    bare.clear_compensation();
    const core::HybridSetup bare_setup = study::setup_for_case(prepared, bare);
    result.compensated = judge_compensated_loop(
        setup, prepared.base.partition.experimental_stiffness(), study_case,
        study::check_setup_critical_delay(prepared, bare_setup,
                                          study::answer_lag(bare_setup) + options.extra_lag));
  }
  for (std::size_t a = 0; a < setup.predictors.size(); ++a)
    if (setup.predictors[a]) result.predicted_actuators.push_back(static_cast<int>(a));
  for (const core::LinkModel& link : setup.links)
    result.link_answers.push_back(core::link_answer_stats(
        core::link_answer_steps(link, setup.dt, prepared.motion.acceleration.size())));
  if (study_case.has_force_predictor())
    result.compensated = judge_predicted_loop(setup, study_case, options.extra_lag);
  if (const auto warning = pre_run_warning(result); warning && options.warn)
    options.warn("case '" + result.name + "': " + *warning);
  return result;
}

// "its envelope grows exponentially over its last 33 cycles of 0.3 s: 0.35 /s, doubling every
// 1.98 s (fit r^2 0.99)", or "... does not grow ...: -0.2 /s".
std::string describe_growth(const core::EnvelopeGrowth& g) {
  std::ostringstream out;
  out << std::setprecision(3) << "its envelope "
      << (g.grows() ? "grows exponentially" : "does not grow") << " over its last " << g.windows
      << " cycles of " << g.period << " s: " << g.rate << " /s";
  if (g.rate > 0.0) out << ", doubling every " << g.doubling_time << " s";
  out << " (fit r^2 " << g.r_squared << ")";
  return out.str();
}

// The verdict a case's lines cite: its compensated loop's where that was analysed (the
// uncompensated check would contradict it), else its critical-delay check's.
std::string governing_verdict(const CaseOutcome& c) {
  if (c.compensated && c.compensated->analysed) return c.compensated->text;
  return c.stability ? c.stability->describe() : std::string("no critical-delay check");
}

// Whether the case's envelope grows beyond the lag-free run's over the same windows: growth the
// lag-free run shares (a short record ending in its strong motion) is the motion's, not the
// loop's. It counts when the lag-free envelope does not grow, or when the case's outgrows it by
// at least a doubling over the fitted span (the margin EnvelopeGrowth::grows() asks of growth).
bool grows_beyond_lag_free(const CaseOutcome& result, const std::vector<double>& lag_free) {
  if (!result.growth || !result.growth->grows()) return false;
  const std::size_t steps = std::min(lag_free.size(), result.response.size());
  const std::optional<core::EnvelopeGrowth> reference = core::envelope_growth(
      std::span(lag_free).first(steps), result.simulation.dt, result.growth->period);
  if (!reference || !(reference->rate > 0.0)) return true;
  return (result.growth->rate - reference->rate) * result.growth->span >= std::log(2.0);
}

// The status of a case that ran, judged from its response against the lag-free run's and from
// its envelope's growth beyond the lag-free run's.
void judge_case(CaseOutcome& result, const std::vector<double>& lag_free_response, int floors) {
  result.response = floor_history(result.simulation, floors - 1);
  if (result.stability && result.stability->governing_period > 0.0 && result.simulation.dt > 0.0)
    result.growth = core::envelope_growth(result.response, result.simulation.dt,
                                          result.stability->governing_period);
  // Past its critical delay, any growth is the loop's (the analysis expects it); inside it, only
  // growth beyond the lag-free run's, which the motion alone does not explain.
  const bool grows_at_all = result.growth && result.growth->grows();
  const bool grows = grows_beyond_lag_free(result, lag_free_response);
  const Comparison growth = compare(lag_free_response, result.response, result.simulation.diverged);
  if (result.status != "completed") return;
  std::ostringstream why;
  why << std::setprecision(4);
  if (growth.diverged) {
    result.status = "diverged";
    why << "peak " << growth.peak_m * 1e3 << " mm against " << growth.peak_reference_m * 1e3
        << " mm without lag (more than " << core::kDivergenceGrowth << "x";
    if (result.simulation.diverged && !result.simulation.time.empty())
      why << "; the simulation stopped at t = " << result.simulation.time.back() << " s";
    why << ")";
    if (result.stability) why << "; " << result.stability->describe();
  } else if (grows_at_all && result.judged_past()) {
    result.status = "diverging";
    why << "past its critical delay and " << describe_growth(*result.growth) << "; peak "
        << growth.peak_m / growth.peak_reference_m << "x the lag-free run's; "
        << governing_verdict(result);
  } else if (grows) {
    why << (result.compensated && result.compensated->analysed
                ? "its compensated loop analysed stable"
                : "inside its critical delay")
        << ", yet " << describe_growth(*result.growth)
        << " beyond the lag-free run's (forcing late in the record, or a limit the check does not "
           "see): "
        << governing_verdict(result);
  } else if (result.judged_past() && !result.compensated) {
    why << std::setprecision(3) << "past its critical delay, but "
        << (result.growth ? describe_growth(*result.growth)
                          : std::string("the record is too short to fit its envelope's growth"))
        << ", and its peak is " << growth.peak_m / growth.peak_reference_m
        << "x the lag-free run's; a longer record may still grow: " << result.stability->describe();
  } else {
    return;
  }
  result.status_detail = why.str();
}

}  // namespace

std::optional<core::CriticalDelayCheck> check_case_critical_delay(
    const study::PreparedStudy& prepared, const config::Case& study_case, double extra_lag) {
  const core::HybridSetup setup = study::setup_for_case(prepared, study_case);
  return study::check_setup_critical_delay(prepared, setup, study::answer_lag(setup) + extra_lag);
}

std::optional<CompensatedVerdict> predicted_loop_verdict(const study::PreparedStudy& prepared,
                                                         const config::Case& study_case,
                                                         double extra_lag) {
  if (!study_case.has_force_predictor()) return std::nullopt;
  const core::HybridSetup setup = study::setup_for_case(prepared, study_case);
  return judge_predicted_loop(setup, study_case, extra_lag);
}

CaseOutcome pre_run_verdict(const study::PreparedStudy& prepared, const std::string& case_name) {
  const config::Case& c = study::find_case(prepared.config, case_name);
  const core::HybridSetup setup = study::setup_for_case(prepared, c);
  return describe_case(
      prepared, setup, c, c.name(), {},
      study::check_setup_critical_delay(prepared, setup, study::answer_lag(setup)));
}

bool CaseOutcome::judged_past() const {
  if (compensated && compensated->analysed) return !compensated->stable;
  return stability && stability->past();
}

const CaseOutcome& StudyOutcome::reference() const {
  return lag_free_reference ? *lag_free_reference : cases.at(reference_index);
}

std::string StudyOutcome::reference_description() const {
  return lag_free_reference ? std::string(kLagFreeReference) : "case '" + reference().name + "'";
}

namespace {

// SHA-256 of the file the motion was read from: the one a record carries with its embedded
// motion, else the file's (relative to the study's folder); "" for a motion from no file.
std::string motion_file_sha256(const study::PreparedStudy& prepared) {
  const config::GroundMotion& motion = prepared.config.motion();
  if (motion.has_embedded()) return motion.embedded().source_sha256();
  if (motion.path().empty()) return "";
  std::filesystem::path path = motion.path();
  if (path.is_relative()) path = prepared.base_dir / path;
  return util::file_sha256(path);
}

// The units the record was read in (its file's, else the config's), one line on it as read, and
// which motion it is (name and checksums).
void read_motion_facts(const study::PreparedStudy& prepared, StudyOutcome& outcome) {
  outcome.motion_units = prepared.motion.read_units.empty()
                             ? study::motion_units_name(prepared.config.motion())
                             : prepared.motion.read_units;
  outcome.motion_description = prepared.motion.description;
  outcome.motion_name = prepared.motion.name;
  outcome.motion_sha256 = study::motion_key(prepared.motion);
  outcome.motion_file_sha256 = motion_file_sha256(prepared);
}

// An outcome of no case yet: the study's name, recorders, actuators, motion and response.
StudyOutcome empty_outcome(const study::PreparedStudy& prepared) {
  StudyOutcome outcome;
  outcome.study_name = prepared.config.name();
  outcome.recorders = prepared.recorders;
  outcome.actuators = actuator_names(prepared.config, prepared.base.partition);
  read_motion_facts(prepared, outcome);
  outcome.response = ResponseSpec::top_floor(prepared.base.model.dofs());
  return outcome;
}

// A case's stop before the record's end: a limit tripped (its history cut before that step,
// whose command is never sent) or its force predictor's hold.
void apply_stops(CaseOutcome& result, const config::SafetyLimits& limits) {
  if (const auto trip = first_limit_trip(result.simulation, limits)) {
    result.simulation.truncate(trip->first);
    result.status = "limit tripped";
    result.status_detail = trip->second;
  }
  if (!result.simulation.held.empty()) {
    result.status = "held";
    result.status_detail = result.simulation.held;
  }
}

}  // namespace

StudyOutcome run_study(const study::PreparedStudy& prepared, const RunStudyOptions& options) {
  const config::Study& study = prepared.config;
  if (options.warn)
    for (const std::string& warning : prepared.warnings) options.warn(warning);
  config::Study with_cases = study;
  if (with_cases.cases_size() == 0) with_cases.add_cases()->set_name("reference");
  const config::Case& reference = study::reference_case(with_cases);
  const int floors = prepared.base.model.dofs();

  StudyOutcome outcome = empty_outcome(prepared);
  // The lag-free run: what growth is judged against (a lagged reference case would hide it).
  const core::SimulationOptions kept =
      study::kept_by_recorders(prepared.recorders, prepared.config.deployment().limits());
  // Each case's setup built once, one model alive at a time: its loop, then its run.
  std::vector<const config::Case*> cases;
  std::size_t simulations = 1;  // the lag-free run and each case that adds to it
  for (const config::Case& study_case : with_cases.cases()) {
    cases.push_back(&study_case);
    simulations += adds_nothing(study_case) ? 0 : 1;
  }
  CaseSetups setups(prepared, cases, options.extra_lag);
  SharedChecks checks(setups.loops());
  RunProgress progress(options.progress, simulations, prepared.motion.acceleration.size());
  progress.start(0, "the lag-free run");
  const core::SimulationResult lag_free =
      core::simulate(prepared.base, prepared.motion, kept, {}, &progress);
  const std::vector<double> lag_free_response = floor_history(lag_free, floors - 1);
  outcome.lag_free_peak = core::peak_abs(lag_free_response);

  std::size_t run = 1;
  for (int i = 0; i < with_cases.cases_size(); ++i) {
    const config::Case& study_case = with_cases.cases(i);
    if (&study_case == &reference) outcome.reference_index = static_cast<std::size_t>(i);
    const core::HybridSetup& setup = setups.lend(static_cast<std::size_t>(i));
    CaseOutcome result =
        describe_case(prepared, setup, study_case,
                      study_case.name().empty() ? "case" + std::to_string(i) : study_case.name(),
                      options, checks.for_case(prepared, static_cast<std::size_t>(i), setup));
    // A case that adds nothing to the base is the lag-free run itself: its steps are not
    // integrated twice.
    if (!adds_nothing(study_case)) progress.start(run++, "case '" + result.name + "'");
    result.simulation = adds_nothing(study_case)
                            ? lag_free
                            : core::simulate(setup, prepared.motion, kept, {}, &progress);
    apply_stops(result, study.deployment().limits());
    judge_case(result, lag_free_response, floors);
    outcome.cases.push_back(std::move(result));
  }
  const CaseOutcome& ref = outcome.cases[outcome.reference_index];
  for (CaseOutcome& c : outcome.cases) {
    c.comparison = compare(ref.simulation, c.simulation, outcome.response);
  }
  return outcome;
}

StudyOutcome judge_recorded_cases(const study::PreparedStudy& prepared,
                                  std::vector<RecordedCase> recorded,
                                  const RunStudyOptions& options) {
  if (recorded.empty()) throw std::invalid_argument("judge_recorded_cases: no cases");
  const int floors = prepared.base.model.dofs();
  StudyOutcome outcome = empty_outcome(prepared);
  CaseOutcome lag_free;
  lag_free.name = "lag_free_in_process";
  lag_free.delay_description = "none (in process, no delay stage)";
  // What the records keep: the recorders' DOFs (the coordinator's loop keeps the same).
  lag_free.simulation = core::simulate(
      prepared.base, prepared.motion,
      study::kept_by_recorders(prepared.recorders, prepared.config.deployment().limits()));
  lag_free.response = floor_history(lag_free.simulation, floors - 1);
  outcome.lag_free_peak = core::peak_abs(lag_free.response);
  std::vector<const config::Case*> study_cases;
  for (const RecordedCase& r : recorded) {
    const config::Case* study_case = nullptr;
    for (const config::Case& c : prepared.config.cases())
      if (c.name() == r.name) study_case = &c;
    if (study_case == nullptr)
      throw std::invalid_argument("case '" + r.name + "' is not among the study's cases");
    study_cases.push_back(study_case);
  }
  CaseSetups setups(prepared, study_cases, options.extra_lag);
  SharedChecks checks(setups.loops());
  for (std::size_t i = 0; i < recorded.size(); ++i) {
    RecordedCase& r = recorded[i];
    const core::HybridSetup& setup = setups.lend(i);
    CaseOutcome result = describe_case(prepared, setup, *study_cases[i], r.name, options,
                                       checks.for_case(prepared, i, setup));
    result.simulation = std::move(r.simulation);
    result.status = r.status;
    if (result.status != "completed") result.status_detail = r.status_detail;
    judge_case(result, lag_free.response, floors);
    result.comparison = compare(lag_free.simulation, result.simulation, outcome.response);
    outcome.cases.push_back(std::move(result));
  }
  lag_free.comparison = compare(lag_free.simulation, lag_free.simulation, outcome.response);
  outcome.lag_free_reference = std::move(lag_free);
  return outcome;
}

}  // namespace rths::analysis
