#include "analysis/study_run.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <exception>
#include <future>
#include <iomanip>
#include <numbers>
#include <sstream>
#include <tuple>

#include "analysis/results_csv.h"
#include "core/metrics.h"
#include "util/atomic_file.h"
#include "util/plot.h"
#include "util/text_table.h"

namespace rths::analysis {
namespace {

// The first step at which |u| or |v| of a floor passed a limit (0 = no limit), with why.
std::optional<std::pair<std::size_t, std::string>> first_limit_trip(
    const core::SimulationResult& r, const config::SafetyLimits& limits) {
  for (std::size_t k = 0; k < r.steps(); ++k) {
    const auto row = static_cast<Eigen::Index>(k);
    for (Eigen::Index i = 0; i < r.displacement.cols(); ++i) {
      std::ostringstream why;
      why << std::setprecision(4);
      if (limits.max_displacement() > 0 &&
          !(std::abs(r.displacement(row, i)) <= limits.max_displacement())) {
        why << "|u| of floor " << i + 1 << " = " << std::abs(r.displacement(row, i))
            << " m > limit " << limits.max_displacement() << " m at t = " << r.time[k] << " s";
        return std::make_pair(k, why.str());
      }
      if (limits.max_velocity() > 0 && !(std::abs(r.velocity(row, i)) <= limits.max_velocity())) {
        why << "|v| of floor " << i + 1 << " = " << std::abs(r.velocity(row, i)) << " m/s > limit "
            << limits.max_velocity() << " m/s at t = " << r.time[k] << " s";
        return std::make_pair(k, why.str());
      }
    }
  }
  return std::nullopt;
}

std::string ms(double seconds) {
  std::ostringstream out;
  out << std::setprecision(3) << seconds * 1e3 << " ms";
  return out.str();
}

}  // namespace

std::vector<std::string> StudyOutcome::failures(bool allow_unstable) const {
  std::vector<std::string> out;
  for (const CaseOutcome& c : cases) {
    if (c.status == "limit tripped")
      out.push_back("case '" + c.name + "': limit tripped: " + c.status_detail);
    if (c.diverged() && !c.expect_unstable && !allow_unstable) {
      out.push_back("case '" + c.name +
                    (c.status == "diverging" ? "' is diverging: " : "' diverged: ") +
                    c.status_detail);
    }
  }
  return out;
}

namespace {

double nominal_delay_of(const core::HybridSetup& setup) {
  double nominal = 0.0;
  for (const core::DelayChain& chain : setup.delays)
    nominal = std::max(nominal, chain.nominal_delay());
  return nominal;
}

std::optional<core::CriticalDelayCheck> check_setup(const core::PreparedStudy& prepared,
                                                    const core::HybridSetup& setup, double lag) {
  if (prepared.base.partition.actuator_storeys.empty()) return std::nullopt;
  return core::check_modal_critical_delay(setup.model,
                                          prepared.base.partition.experimental_stiffness(),
                                          setup.integrator, setup.dt, lag);
}

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
  const core::Modes modes = core::modal_analysis(model.mass, model.stiffness);
  std::vector<ModalSdof> out;
  for (int i = 0; i < model.dofs(); ++i) {
    const double omega = modes.omega[i];
    const core::Vec phi = modes.shapes.col(i);
    const double alpha = std::clamp(phi.dot(k_experimental * phi) / (omega * omega), 0.0, 1.0);
    if (!(alpha > 0.0)) continue;
    out.push_back({i + 1, 2.0 * std::numbers::pi / omega,
                   phi.dot(model.damping * phi) / (2.0 * omega), alpha});
  }
  return out;
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
  const bool modal = setup.model.dofs() > 1;
  try {
    bool stable = true;
    double radius = 0.0;
    int unstable_mode = 0, governing = 0;
    std::optional<double> margin;
    bool unbounded = true;  // every mode stable up to the searched range
    std::string linearised;
    for (const ModalSdof& sdof : sdofs) {
      const core::CompensatedStability loop = core::compensated_stability(
          setup.integrator, sdof.period, sdof.zeta, sdof.alpha, setup.dt, study_case.delay(),
          &study_case.compensation(0), kMaxExtraDelay);
      if (!loop.frozen_coefficients.empty()) {
        verdict.text =
            "adaptive compensation: its coefficients change during the run, so its loop cannot "
            "be judged before it" +
            beside;
        return verdict;
      }
      if (!loop.linearised.empty()) linearised = loop.linearised;
      if (!loop.stable) {
        if (stable) {
          radius = loop.spectral_radius;
          unstable_mode = sdof.mode;
        }
        stable = false;
        continue;
      }
      std::optional<double> mode_margin = loop.continuous_margin;
      if (loop.discrete_margin)
        mode_margin =
            mode_margin ? std::min(*mode_margin, *loop.discrete_margin) : loop.discrete_margin;
      if (mode_margin) {
        unbounded = false;
        if (!margin || *mode_margin < *margin) {
          margin = mode_margin;
          governing = sdof.mode;
        }
      }
    }
    verdict.analysed = true;
    verdict.stable = stable;
    std::ostringstream text;
    text << std::setprecision(3) << "compensated loop: ";
    if (!stable) {
      text << "UNSTABLE as configured (spectral radius " << radius;
      if (modal) text << ", mode " << unstable_mode;
      text << ")";
    } else {
      verdict.extra_delay_tolerated = margin;
      if (margin && !unbounded) {
        text << "stable, tolerates " << *margin * 1e3 << " ms more lag";
        if (modal) text << " (mode " << governing << " governs)";
      } else {
        text << "stable for up to " << kMaxExtraDelay * 1e3 << " ms more lag (searched)";
      }
    }
    if (modal)
      text << " (modal approximation over the " << sdofs.size()
           << " modes with experimental stiffness, each an SDOF; the coupling the delayed force "
              "adds between modes is ignored)";
    if (!linearised.empty()) text << " (linearised: " << linearised << ")";
    verdict.text = text.str() + beside;
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

// What is known of a case before it runs: its delay, and its critical-delay check (announced
// through options.warn when past; for a compensated case, its compensated loop's verdict).
CaseOutcome describe_case(const core::PreparedStudy& prepared, const core::HybridSetup& setup,
                          const config::Case& study_case, const std::string& name,
                          const RunStudyOptions& options) {
  CaseOutcome result;
  result.name = name;
  result.expect_unstable = study_case.expect_unstable();
  result.nominal_delay = nominal_delay_of(setup);
  result.delay_description =
      setup.delays.empty() ? "no experimental substructure" : setup.delays.front().describe();
  result.stability = check_setup(prepared, setup, result.nominal_delay + options.extra_lag);
  if (study_case.compensation_size() > 0) {
    // Beside the compensated loop's verdict: the same case without its compensators.
    config::Case bare = study_case;
    bare.clear_compensation();
    const core::HybridSetup bare_setup = core::setup_for_case(prepared, bare);
    result.compensated = judge_compensated_loop(
        setup, prepared.base.partition.experimental_stiffness(), study_case,
        check_setup(prepared, bare_setup, nominal_delay_of(bare_setup) + options.extra_lag));
  }
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

// The status of a case that ran, judged from its response against the lag-free run's and from
// its envelope's growth.
void judge_case(CaseOutcome& result, const std::vector<double>& lag_free_response, int floors) {
  result.response = floor_history(result.simulation, floors - 1);
  if (result.stability && result.stability->governing_period > 0.0 && result.simulation.dt > 0.0)
    result.growth = core::envelope_growth(result.response, result.simulation.dt,
                                          result.stability->governing_period);
  const bool grows = result.growth && result.growth->grows();
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
  } else if (grows && result.judged_past()) {
    result.status = "diverging";
    why << "past its critical delay and " << describe_growth(*result.growth) << "; peak "
        << growth.peak_m / growth.peak_reference_m << "x the lag-free run's; "
        << result.stability->describe();
  } else if (grows) {
    why << "inside its critical delay, yet " << describe_growth(*result.growth)
        << " (forcing late in the record, or a limit the check does not see): "
        << result.stability->describe();
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
    const core::PreparedStudy& prepared, const config::Case& study_case, double extra_lag) {
  const core::HybridSetup setup = core::setup_for_case(prepared, study_case);
  return check_setup(prepared, setup, nominal_delay_of(setup) + extra_lag);
}

std::optional<core::CriticalDelayCheck> check_lag_critical_delay(
    const core::PreparedStudy& prepared, double lag) {
  return check_setup(prepared, prepared.base, lag);
}

CaseOutcome pre_run_verdict(const core::PreparedStudy& prepared, const std::string& case_name) {
  for (const config::Case& c : prepared.config.cases())
    if (c.name() == case_name)
      return describe_case(prepared, core::setup_for_case(prepared, c), c, c.name(), {});
  throw std::invalid_argument("case '" + case_name + "' is not among the study's cases");
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

StudyOutcome run_study(const core::PreparedStudy& prepared, const RunStudyOptions& options) {
  const config::Study& study = prepared.config;
  config::Study with_cases = study;
  if (with_cases.cases_size() == 0) with_cases.add_cases()->set_name("reference");
  const config::Case& reference = core::reference_case(with_cases);
  const int floors = prepared.base.model.dofs();

  StudyOutcome outcome;
  outcome.study_name = study.name();
  outcome.motion_units = core::motion_units_name(study.motion());
  outcome.response = ResponseSpec::top_floor(floors);
  // The lag-free run: what growth is judged against (a lagged reference case would hide it).
  const core::SimulationResult lag_free = core::simulate(prepared.base, prepared.motion);
  const std::vector<double> lag_free_response = floor_history(lag_free, floors - 1);
  outcome.lag_free_peak = core::peak_abs(lag_free_response);

  for (int i = 0; i < with_cases.cases_size(); ++i) {
    const config::Case& study_case = with_cases.cases(i);
    if (&study_case == &reference) outcome.reference_index = static_cast<std::size_t>(i);
    const core::HybridSetup setup = core::setup_for_case(prepared, study_case);
    CaseOutcome result = describe_case(
        prepared, setup, study_case,
        study_case.name().empty() ? "case" + std::to_string(i) : study_case.name(), options);
    result.simulation = core::simulate(setup, prepared.motion);
    if (const auto trip = first_limit_trip(result.simulation, study.deployment().limits())) {
      result.simulation.truncate(trip->first);  // the command of that step is never sent
      result.status = "limit tripped";
      result.status_detail = trip->second;
    }
    judge_case(result, lag_free_response, floors);
    outcome.cases.push_back(std::move(result));
  }
  const CaseOutcome& ref = outcome.cases[outcome.reference_index];
  for (CaseOutcome& c : outcome.cases) {
    c.comparison = compare(ref.simulation, c.simulation, outcome.response);
  }
  return outcome;
}

StudyOutcome judge_recorded_cases(const core::PreparedStudy& prepared,
                                  std::vector<RecordedCase> recorded,
                                  const RunStudyOptions& options) {
  if (recorded.empty()) throw std::invalid_argument("judge_recorded_cases: no cases");
  const int floors = prepared.base.model.dofs();
  StudyOutcome outcome;
  outcome.study_name = prepared.config.name();
  outcome.motion_units = core::motion_units_name(prepared.config.motion());
  outcome.response = ResponseSpec::top_floor(floors);
  CaseOutcome lag_free;
  lag_free.name = "lag_free_in_process";
  lag_free.delay_description = "none (in process, no delay stage)";
  lag_free.simulation = core::simulate(prepared.base, prepared.motion);
  lag_free.response = floor_history(lag_free.simulation, floors - 1);
  outcome.lag_free_peak = core::peak_abs(lag_free.response);
  for (RecordedCase& r : recorded) {
    const config::Case* study_case = nullptr;
    for (const config::Case& c : prepared.config.cases())
      if (c.name() == r.name) study_case = &c;
    if (study_case == nullptr)
      throw std::invalid_argument("case '" + r.name + "' is not among the study's cases");
    CaseOutcome result = describe_case(prepared, core::setup_for_case(prepared, *study_case),
                                       *study_case, r.name, options);
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

std::vector<std::string> study_plot_files() {
  return {"displacement.png",       "displacement.svg", "force_displacement.png",
          "force_displacement.svg", "tracking.png",     "tracking.svg"};
}

namespace {

// Start of the `window` seconds of the reference with the most energy (sum of u^2).
double strongest_window_start(const std::vector<double>& u, double dt, double window) {
  const std::size_t length =
      std::min(u.size(), static_cast<std::size_t>(std::llround(window / dt)));
  if (length == 0 || length >= u.size()) return 0.0;
  double energy = 0.0;
  for (std::size_t k = 0; k < length; ++k) energy += u[k] * u[k];
  double best = energy;
  std::size_t best_start = 0;
  for (std::size_t start = 1; start + length <= u.size(); ++start) {
    energy += u[start + length - 1] * u[start + length - 1] - u[start - 1] * u[start - 1];
    if (energy > best) {
      best = energy;
      best_start = start;
    }
  }
  return static_cast<double>(best_start) * dt;
}

}  // namespace

namespace {

// " (within X mm of NAME)" when case i's response stays within 5 % of its peak of an earlier
// drawn case's, so that a reader told the curves overlap looks for both; else "".
std::string coincides_with(const std::vector<const CaseOutcome*>& drawn, std::size_t i) {
  const std::vector<double>& r = drawn[i]->response;
  const double peak = core::peak_abs(r);
  for (std::size_t j = 0; j < i; ++j) {
    const CaseOutcome& other = *drawn[j];
    if (other.diverged() || other.response.size() != r.size() || peak <= 0.0) continue;
    double largest = 0.0;
    for (std::size_t k = 0; k < r.size(); ++k)
      largest = std::max(largest, std::abs(r[k] - other.response[k]));
    if (largest > 0.05 * peak) continue;
    char within[64];
    std::snprintf(within, sizeof within, " (within %.2g mm of ", largest * 1e3);
    std::string text = within;
    text += other.name;
    text += ')';
    return text;
  }
  return "";
}

// The first actuator's measured force (kN) against its command (mm).
util::Series force_loop(const CaseOutcome& c, const std::string& label, const std::string& style) {
  util::Series loop{label, {}, {}, style};
  for (Eigen::Index k = 0; k < c.simulation.command.rows(); ++k) {
    loop.x.push_back(c.simulation.command(k, 0) * 1e3);
    loop.y.push_back(c.simulation.measured_force(k, 0) * 1e-3);
  }
  return loop;
}

// force_displacement.png: what the integrator sees of the experimental part, one panel per case
// with the reference drawn over it, thin and dark. Without lag the reference's loop is a line
// that every lagged case's ellipse would cover on a shared panel, and cases with near-equal
// loops would cover each other. A diverged case has no loop worth drawing.
void write_force_displacement(const std::string& study,
                              const std::vector<const CaseOutcome*>& drawn,
                              const CaseOutcome& reference, const std::filesystem::path& png) {
  const auto has_loop = [](const CaseOutcome& c) {
    return c.simulation.command.cols() > 0 && !c.diverged();
  };
  if (!has_loop(reference)) return;
  const util::Series over =
      force_loop(reference, reference.name + " (drawn over)", "lines lc rgb '#222222' dt 1 lw 1.2");
  std::vector<util::PlotSpec> panels;
  for (std::size_t i = 0; i < drawn.size(); ++i) {
    const CaseOutcome& c = *drawn[i];
    if (&c == &reference || !has_loop(c)) continue;
    util::PlotSpec panel{
        study + ": what the integrator sees, " + c.name + " against " + reference.name,
        "commanded displacement (mm)", "measured force (kN)"};
    panel.series = {
        force_loop(c, c.name, "lines lc rgb '" + util::series_colour(i) + "' dt 1 lw 2"), over};
    panel.height = 340;
    panels.push_back(std::move(panel));
  }
  // One scale on every panel, so that the loops compare at a glance.
  std::vector<util::Series> all, swapped;
  for (const util::PlotSpec& p : panels)
    for (const util::Series& s : p.series) {
      all.push_back(s);
      swapped.push_back({s.title, s.y, s.x});
    }
  const auto y = util::padded_y_range(all, {}, 0.04), x = util::padded_y_range(swapped, {}, 0.04);
  for (util::PlotSpec& p : panels) {
    if (y) std::tie(p.y_min, p.y_max) = *y;
    if (x) std::tie(p.x_min, p.x_max) = *x;
  }
  if (panels.empty()) {
    util::PlotSpec alone{study + ": what the integrator sees (experimental part)",
                         "commanded displacement (mm)", "measured force (kN)"};
    alone.series = {force_loop(reference, reference.name, "lines lw 2")};
    panels.push_back(std::move(alone));
  }
  util::write_png_panels(panels, png);
}

// tracking.png, the RTHS benchmark's tracking figure: per case that drives an actuator and stayed
// bounded, x_t (the command of the first actuator) and x_m (what it measured there), mm, over the
// record, then the same over `zoom` s from `zoom_start` (s), where the lag between them shows.
// Nothing when no such case.
void write_tracking(const std::string& study, const std::vector<const CaseOutcome*>& drawn,
                    const CaseOutcome& reference, double zoom_start, double zoom,
                    const std::filesystem::path& png) {
  std::vector<util::PlotSpec> panels;
  for (const CaseOutcome* c : drawn) {
    if (c == &reference || c->diverged() || c->simulation.command.cols() == 0 ||
        c->simulation.realised.cols() == 0)
      continue;
    util::PlotSpec whole{study + ": tracking of " + c->name + ", x_t (command) and x_m (measured)",
                         "time (s)", "displacement at actuator 1 (mm)"};
    util::Series target{"x_t, command", c->simulation.time, {}, "lines lw 2"};
    util::Series measured{"x_m, measured", c->simulation.time, {}, "lines lw 1"};
    for (Eigen::Index k = 0; k < c->simulation.command.rows(); ++k) {
      target.y.push_back(c->simulation.command(k, 0) * 1e3);
      measured.y.push_back(c->simulation.realised(k, 0) * 1e3);
    }
    target.x.resize(target.y.size());
    measured.x.resize(measured.y.size());
    whole.series = {target, measured};
    util::PlotSpec close = whole;
    char title[160];
    std::snprintf(title, sizeof title, "zoom: %s over %g s at the reference's strongest",
                  c->name.c_str(), zoom);
    close.title = title;
    close.x_min = zoom_start;
    close.x_max = zoom_start + zoom;
    // The zoom's y range follows what is in its window.
    double lo = 0.0, hi = 0.0;
    for (std::size_t k = 0; k < target.x.size(); ++k) {
      if (target.x[k] < zoom_start || target.x[k] > zoom_start + zoom) continue;
      lo = std::min({lo, target.y[k], measured.y[k]});
      hi = std::max({hi, target.y[k], measured.y[k]});
    }
    if (hi > lo) {
      close.y_min = lo - 0.08 * (hi - lo);
      close.y_max = hi + 0.08 * (hi - lo);
    }
    whole.height = close.height = 340;
    panels.push_back(std::move(whole));
    panels.push_back(std::move(close));
  }
  if (!panels.empty()) util::write_png_panels(panels, png);
}

}  // namespace

void write_study_plots(const StudyOutcome& outcome, const std::filesystem::path& directory) {
  std::filesystem::create_directories(directory);
  const CaseOutcome& reference = outcome.reference();
  const std::string response = outcome.response.describe();
  util::PlotSpec displacement{outcome.study_name + ": " + response + " displacement, every case",
                              "time (s)",
                              "displacement (mm)",
                              {}};
  util::PlotSpec difference{"difference from the reference (" + reference.name + ")",
                            "time (s)",
                            "case - reference (mm)",
                            {}};
  std::vector<std::size_t> bounded, bounded_difference;  // series that set the axes
  std::vector<const CaseOutcome*> drawn;  // the lag-free reference first, when it is not a case
  if (outcome.lag_free_reference) drawn.push_back(&*outcome.lag_free_reference);
  for (const CaseOutcome& c : outcome.cases) drawn.push_back(&c);
  for (std::size_t i = 0; i < drawn.size(); ++i) {
    const CaseOutcome& c = *drawn[i];
    const std::string label =
        c.name + (c.diverged() ? " (" + c.status + ", clipped)" : coincides_with(drawn, i));
    // Each case keeps its colour on every panel and is drawn thinner than the case before it, so
    // that two cases whose responses coincide are both seen (solid: cairo draws a dashed line of
    // 10^4 points very slowly).
    const std::string style = "lines lc rgb '" + util::series_colour(i) + "' dt 1 lw " +
                              std::to_string(std::max(0.7, 3.0 - 0.8 * static_cast<double>(i)));
    util::Series s{label, c.simulation.time, {}, style};
    for (double u : c.response) s.y.push_back(u * 1e3);
    if (!c.diverged()) bounded.push_back(displacement.series.size());
    displacement.series.push_back(std::move(s));
    if (&c != &reference) {
      // The reference against itself is a zero line that says nothing: it is left out.
      util::Series d{label, c.simulation.time, {}, style};
      for (std::size_t k = 0; k < c.response.size() && k < reference.response.size(); ++k) {
        d.y.push_back((c.response[k] - reference.response[k]) * 1e3);
      }
      if (!c.diverged()) bounded_difference.push_back(difference.series.size());
      difference.series.push_back(std::move(d));
    }
  }
  // A diverged case must not flatten the others: the axes follow the cases that stayed bounded.
  if (const auto r = util::padded_y_range(displacement.series, bounded)) {
    displacement.y_min = r->first;
    displacement.y_max = r->second;
  }
  if (const auto r = util::padded_y_range(difference.series, bounded_difference)) {
    difference.y_min = r->first;
    difference.y_max = r->second;
  }
  util::PlotSpec zoom = displacement;
  const double start = strongest_window_start(reference.response, reference.simulation.dt, 5.0);
  zoom.title = "zoom: the strongest 5 s of the reference";
  zoom.x_min = start;
  zoom.x_max = start + 5.0;
  std::vector<util::PlotSpec> panels = {displacement};
  if (!difference.series.empty()) panels.push_back(difference);
  panels.push_back(zoom);
  for (util::PlotSpec& p : panels) p.height = 380;
  // A stale tracking figure must not stay beside a study that has none.
  std::filesystem::remove(directory / "tracking.png");
  std::filesystem::remove(directory / "tracking.svg");
  // The three figures are independent (each its own gnuplot and files): drawn at once, so their
  // wall-clock time is the slowest one's where there are cores for them. Any failure is rethrown.
  std::vector<std::future<void>> figures;
  figures.push_back(std::async(
      std::launch::async, [&] { util::write_png_panels(panels, directory / "displacement.png"); }));
  figures.push_back(std::async(std::launch::async, [&] {
    write_force_displacement(outcome.study_name, drawn, reference,
                             directory / "force_displacement.png");
  }));
  figures.push_back(std::async(std::launch::async, [&] {
    write_tracking(outcome.study_name, drawn, reference,
                   strongest_window_start(reference.response, reference.simulation.dt, 1.0), 1.0,
                   directory / "tracking.png");
  }));
  std::exception_ptr failure;
  for (std::future<void>& figure : figures) {
    try {
      figure.get();
    } catch (...) {
      if (!failure) failure = std::current_exception();
    }
  }
  if (failure) std::rethrow_exception(failure);
}

namespace {

nlohmann::json compensated_json(const std::optional<CompensatedVerdict>& v) {
  if (!v) return nullptr;
  return {{"analysed", v->analysed},
          {"stable", v->analysed ? nlohmann::json(v->stable) : nlohmann::json()},
          {"extra_delay_tolerated_s",
           v->extra_delay_tolerated ? nlohmann::json(*v->extra_delay_tolerated) : nlohmann::json()},
          {"verdict", v->text}};
}

nlohmann::json growth_json(const std::optional<core::EnvelopeGrowth>& g) {
  if (!g) return nullptr;
  return {{"grows", g->grows()},
          {"rate_per_s", g->rate},
          {"doubling_time_s", g->rate > 0.0 ? nlohmann::json(g->doubling_time) : nlohmann::json()},
          {"r_squared", g->r_squared},
          {"cycles", g->windows},
          {"cycle_s", g->period},
          {"span_s", g->span}};
}

}  // namespace

nlohmann::json error_measures_json() {
  return {{"peak_error_pct", kPeakErrorDefinition},
          {"rms_error_pct", kRmsErrorDefinition},
          {"peak_error_m", "max|u - u_ref| (m)"},
          {"nrmse_pct",
           "the paper's normalisation: 100 sqrt(mean (u - u_ref)^2) / median|u_ref| (%); a record "
           "ending in near-zero motion has a tiny median and inflates it"},
          {"paper_eq2_as_printed",
           "the paper's Eq. 2 as printed: sqrt(sum (u - u_ref)^2) / N / "
           "median|u_ref| (shrinks like 1/sqrt(N))"}};
}

nlohmann::json study_summary_json(const StudyOutcome& outcome) {
  nlohmann::json cases = nlohmann::json::array();
  for (const CaseOutcome& c : outcome.cases) {
    nlohmann::json stability = nullptr;
    if (c.stability) {
      const auto& s = *c.stability;
      const auto opt = [](const std::optional<double>& v) {
        return v ? nlohmann::json(*v) : nlohmann::json();
      };
      stability = {
          {"lag_s", s.lag},
          {"continuous_critical_delay_s", opt(s.continuous)},
          {"discrete_critical_delay_s", opt(s.discrete)},
          {"discrete_check",
           s.discrete_skipped.empty() ? "made" : "skipped: " + s.discrete_skipped},
          {"critical_delay_s", opt(s.critical())},
          {"margin_pct", s.critical() ? nlohmann::json(100.0 * s.margin()) : nlohmann::json()},
          {"past_critical_delay", s.past()},
          {"assumed", s.assumed}};
    }
    // A case that stopped early has no error over the steps it did not run: its errors are null,
    // and those over the steps it covered are given apart, named as such.
    const bool covers = c.comparison.covers_reference();
    const auto whole = [covers](double v) { return covers ? nlohmann::json(v) : nlohmann::json(); };
    const nlohmann::json covered =
        covers ? nlohmann::json()
               : nlohmann::json{{"steps", c.comparison.steps_compared},
                                {"peak_error_pct", c.comparison.peak_error_pct},
                                {"rms_error_pct", c.comparison.rms_error_pct},
                                {"peak_error_m", c.comparison.peak_error_m}};
    cases.push_back({{"name", c.name},
                     {"delay", c.delay_description},
                     {"nominal_delay_s", c.nominal_delay},
                     {"status", c.status},
                     {"status_detail", c.status_detail},
                     {"expect_unstable", c.expect_unstable},
                     {"stability", stability},
                     {"compensated_loop", compensated_json(c.compensated)},
                     {"envelope_growth", growth_json(c.growth)},
                     {"peak_displacement_m", c.comparison.peak_m},
                     {"peak_error_pct", whole(c.comparison.peak_error_pct)},
                     {"rms_error_pct", whole(c.comparison.rms_error_pct)},
                     {"peak_error_m", whole(c.comparison.peak_error_m)},
                     {"paper_eq2_as_printed", whole(c.comparison.paper_eq2_as_printed)},
                     {"nrmse_pct", whole(c.comparison.nrmse_pct)},
                     {"steps_compared", c.comparison.steps_compared},
                     {"reference_steps", c.comparison.reference_steps},
                     {"errors_over_covered_steps", covered},
                     {"diverged", c.diverged()},
                     {"steps", c.simulation.steps()}});
  }
  return {{"study", outcome.study_name},
          {"measures", error_measures_json()},
          {"motion_units", outcome.motion_units},
          {"response", outcome.response.describe()},
          {"reference_case", outcome.reference().name},
          {"reference", outcome.reference_description()},
          {"lag_free_peak_m", outcome.lag_free_peak},
          {"cases", cases}};
}

namespace {

std::string fixed(double value, int decimals) {
  std::ostringstream out;
  out << std::fixed << std::setprecision(decimals) << value;
  return out.str();
}

// The row of one case: errors of a response that grew without bound measure nothing (the JSON
// keeps them), so a diverged case shows "-" there.
// The margin cell: the lag's margin against the critical delay; for a compensated case, the
// compensated loop's verdict in short (the lag it tolerates beyond its own, "unstable", or "n/a"
// when it is not analysable), spelled out with the uncompensated margin below the table.
std::string margin_cell(const CaseOutcome& c) {
  if (c.compensated) {
    const CompensatedVerdict& v = *c.compensated;
    if (!v.analysed) return "n/a [comp.]";
    if (!v.stable) return "unstable [comp.]";
    return v.extra_delay_tolerated ? "+" + ms(*v.extra_delay_tolerated) + " [comp.]" : "stable";
  }
  if (c.stability && c.stability->critical()) return fixed(100.0 * c.stability->margin(), 1) + " %";
  return "-";
}

// Errors only for a case that stayed bounded and covered the whole reference: a case that stopped
// early has no error over the steps it did not run ("-", and a line below with the steps it did).
std::vector<std::string> summary_row(const CaseOutcome& c) {
  std::string critical = "-";
  if (c.stability) critical = c.stability->critical() ? ms(*c.stability->critical()) : "none";
  const std::string margin = margin_cell(c);
  const bool measured = !c.diverged() && c.comparison.covers_reference();
  return {c.name,
          c.delay_description,
          fixed(c.comparison.peak_m * 1e3, 3),
          measured ? fixed(c.comparison.peak_error_pct, 2) : "-",
          measured ? fixed(c.comparison.rms_error_pct, 2) : "-",
          measured ? fixed(c.comparison.peak_error_m * 1e3, 3) : "-",
          critical,
          margin,
          c.status + (c.diverged() && c.expect_unstable ? " (expected)" : "")};
}

}  // namespace

std::string study_summary_text(const StudyOutcome& outcome) {
  std::ostringstream out;
  out << "study: " << outcome.study_name << " (every case against "
      << outcome.reference_description() << "; response: " << outcome.response.describe()
      << " displacement; motion read in " << outcome.motion_units << ")\n";
  using Align = util::TextTable::Align;
  util::TextTable table({{"case", Align::kLeft, 40},
                         {"delay", Align::kLeft, 28},
                         {"peak (mm)", Align::kRight},
                         {"E_peak (%)", Align::kRight},
                         {"E_rms (%)", Align::kRight},
                         {"peak err (mm)", Align::kRight},
                         {"crit. delay", Align::kRight},
                         {"margin", Align::kRight},
                         {"status", Align::kLeft, 40}});
  for (const CaseOutcome& c : outcome.cases) table.add_row(summary_row(c));
  out << table.render();
  out << "E_peak: " << kPeakErrorDefinition << "; E_rms: " << kRmsErrorDefinition
      << "; the paper's median-normalised NRMSE and Eq. 2 are in summary.json\n";
  for (const CaseOutcome& c : outcome.cases) {
    if (c.diverged() || c.comparison.covers_reference()) continue;
    out << c.name << ": stopped at step " << c.comparison.steps_compared << " of "
        << c.comparison.reference_steps << ": no error over the steps it did not run; over its "
        << c.comparison.steps_compared << " steps E_peak " << fixed(c.comparison.peak_error_pct, 2)
        << " %, E_rms " << fixed(c.comparison.rms_error_pct, 2) << " %\n";
  }
  if (std::any_of(outcome.cases.begin(), outcome.cases.end(),
                  [](const CaseOutcome& c) { return c.compensated.has_value(); }))
    out << "margin [comp.]: the compensated loop's, as the lag it tolerates beyond its own (n/a: "
           "not analysable before the run); each such case's line below gives it with the "
           "uncompensated margin\n";
  for (const CaseOutcome& c : outcome.cases) {
    if (!c.status_detail.empty()) out << c.name << ": " << c.status_detail << "\n";
    if (c.compensated) out << c.name << ": " << c.compensated->text << "\n";
  }
  return out.str();
}

}  // namespace rths::analysis
