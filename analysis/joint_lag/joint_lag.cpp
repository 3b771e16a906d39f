#include "analysis/joint_lag/joint_lag.h"

#include <fmt/format.h>

#include <google/protobuf/io/tokenizer.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <limits>
#include <map>
#include <numbers>
#include <optional>
#include <sstream>

#include "analysis/common/compare.h"
#include "analysis/joint_lag/joint_lag_plots.h"
#include "analysis/study_run/study_run.h"
#include "core/coupled_stability.h"
#include "core/metrics.h"
#include "core/simulation.h"
#include "core/stability.h"
#include "study/stability_config.h"
#include "study/study.h"
#include "study/text_format.h"
#include "util/plot.h"

namespace rths::analysis {
namespace {

void check_lags(const google::protobuf::RepeatedField<double>& values, const std::string& field,
                const std::string& source, bool required) {
  if (required && values.empty()) throw std::invalid_argument(source + ": " + field + " is empty");
  for (const double v : values) {
    if (!(v >= 0.0) || !std::isfinite(v)) {
      throw std::invalid_argument(source + ": " + field + " must be finite and >= 0");
    }
  }
}

std::string model_name(JointLagStudy::ActuatorModel model) {
  return model == JointLagStudy::FIRST_ORDER ? "first_order" : "shift";
}

// The continuous boundary for an SDOF study; empty (with the reason) otherwise.
void fill_boundary(const JointLagStudy& config, const study::PreparedStudy& prepared,
                   JointLagResult& result) {
  const core::StructuralModel& model = prepared.base.model;
  if (model.mass.rows() != 1) {
    result.boundary_skipped = "the stability boundary is drawn for a one-storey study only";
    return;
  }
  const auto& experimental = prepared.base.partition.experimental;
  const double k = model.stiffness(0, 0), m = model.mass(0, 0);
  const double alpha =
      experimental.empty() || !experimental[0] ? 0.0 : experimental[0]->initial_stiffness() / k;
  const double omega = std::sqrt(k / m), period = 2.0 * std::numbers::pi / omega;
  const double zeta = model.damping(0, 0) / (2.0 * m * omega);
  double largest = 0.0, largest_round_trip = 0.0;
  for (const double a : config.actuator_lags()) largest = std::max(largest, a);
  for (const double r : config.network_round_trips())
    largest_round_trip = std::max(largest_round_trip, r);
  constexpr int kPoints = 41;
  for (int i = 0; i < kPoints; ++i) {
    const double a = largest * i / (kPoints - 1);
    google::protobuf::RepeatedPtrField<config::DelayStage> actuator;
    *actuator.Add() = joint_lag_actuator_stage(config.actuator_model(), a);
    const core::CompensatedStability s = study::compensated_stability(
        prepared.base.integrator, period, zeta, alpha, prepared.base.dt, actuator, nullptr,
        2.0 * largest_round_trip + 0.05);
    result.boundary.push_back({a, s.stable ? s.continuous_margin : std::optional<double>(0.0)});
  }
}

// The compensated loop's boundary (JointLagResult::compensated_boundary): R*(A) = D_p - A, D_p
// the critical lag of the measured pair with every link alike (core::setup_loop_stability: the
// coupled loop of every link with its predictor's model frozen as it starts, any structure), at
// the plain boundary's actuator lags, or at kPoints from 0 to the largest where the structure has
// none (several storeys); nothing without a predictor.
void fill_compensated_boundary(const JointLagStudy& config, const study::PreparedStudy& prepared,
                               JointLagResult& result) {
  if (!config.has_force_predictor()) return;
  config::Case predicted;
  predicted.set_name("predicted");
  *predicted.mutable_force_predictor() = config.force_predictor();
  const core::HybridSetup setup = study::setup_for_case(prepared, predicted);
  const core::CoupledLoopStability loop = core::setup_loop_stability(
      setup, std::vector<double>(setup.partition.actuator_storeys.size(), 0.0));
  const config::ForcePredictor& p = config.force_predictor();
  const double factor = study::predictor_stiffness_factor(p);
  std::ostringstream note;
  note.precision(3);
  note << "with the predictor, its model's stiffness " << std::showpos << 100.0 * (factor - 1.0)
       << std::noshowpos << " % off the specimen's, frozen there ("
       << (p.fixed_model() ? "as configured" : "its online fit only shrinks the error")
       << "), every link at the same lag, the actuator a shift of its lag: ";
  if (loop.common_critical_lag)
    note << "critical lag of the measured pair " << *loop.common_critical_lag * 1e3 << " ms";
  else
    note << "stable at every lag";
  note << " [" << loop.assumed << "]";
  result.compensated_boundary_note = note.str();
  std::vector<double> actuator_lags;
  for (const BoundaryPoint& b : result.boundary) actuator_lags.push_back(b.actuator_lag);
  if (actuator_lags.empty()) {
    constexpr int kPoints = 41;
    double largest = 0.0;
    for (const double a : config.actuator_lags()) largest = std::max(largest, a);
    for (int i = 0; i < kPoints; ++i) actuator_lags.push_back(largest * i / (kPoints - 1));
  }
  for (const double a : actuator_lags) {
    std::optional<double> r;
    if (loop.common_critical_lag) r = std::max(0.0, *loop.common_critical_lag - a);
    result.compensated_boundary.push_back({a, r});
  }
}

std::optional<double> critical_round_trip_at(const JointLagStudy& config,
                                             const study::PreparedStudy& prepared, double a) {
  JointLagResult one;
  JointLagStudy single = config;
  single.clear_actuator_lags();
  single.add_actuator_lags(a);
  fill_boundary(single, prepared, one);
  fill_compensated_boundary(single, prepared, one);
  const auto& boundary = config.has_force_predictor() ? one.compensated_boundary : one.boundary;
  return boundary.empty() ? std::nullopt : boundary.back().critical_round_trip;
}

void write_csv(const std::vector<JointLagPoint>& points, const std::filesystem::path& file) {
  std::ofstream out(file);
  out << "network_round_trip_s,actuator_lag_s,injected_total_s,measured_total_s,"
         "measured_round_trip_s,measured_actuator_lag_s,peak_error_pct,rms_error_pct,"
         "peak_error_m,nrmse_pct,paper_eq2,diverged,past_stability_boundary\n";
  out.precision(10);
  for (const auto& p : points) {
    out << p.network_round_trip << ',' << p.actuator_lag << ','
        << p.network_round_trip + p.actuator_lag << ',' << p.measured_total_lag << ','
        << p.measured_round_trip << ',' << p.measured_actuator_lag << ',' << p.peak_error_pct << ','
        << p.rms_error_pct << ',' << p.peak_error << ',' << 100.0 * p.nrmse << ',' << p.paper_eq2
        << ',' << (p.diverged ? 1 : 0) << ',' << (p.past_boundary ? 1 : 0) << "\n";
  }
  if (!out) throw std::runtime_error("cannot write " + file.string());
}

nlohmann::json point_json(const JointLagPoint& p) {
  nlohmann::json point = {{"network_round_trip_s", p.network_round_trip},
                          {"actuator_lag_s", p.actuator_lag},
                          {"injected_total_s", p.network_round_trip + p.actuator_lag},
                          {"measured_total_s", p.measured_total_lag},
                          {"measured_round_trip_s", p.measured_round_trip},
                          {"measured_actuator_lag_s", p.measured_actuator_lag},
                          {"peak_error_pct", p.peak_error_pct},
                          {"rms_error_pct", p.rms_error_pct},
                          {"peak_error_m", p.peak_error},
                          {"nrmse_pct", 100.0 * p.nrmse},
                          {"paper_eq2", p.paper_eq2},
                          {"past_stability_boundary", p.past_boundary},
                          {"diverged", p.diverged},
                          {"real_time", p.real_time}};
  // Across sites (a run of `duration` s): its in-process counterpart over the same stretch.
  if (p.duration > 0.0) {
    point["in_process_rms_error_pct"] = p.in_process_rms_error_pct;
    point["in_process_nrmse_pct"] = 100.0 * p.in_process_nrmse;
  }
  return point;
}

}  // namespace

config::DelayStage joint_lag_actuator_stage(JointLagStudy::ActuatorModel model, double lag) {
  config::DelayStage stage;
  if (model == JointLagStudy::FIRST_ORDER && lag > 0.0) {
    stage.mutable_first_order()->set_time_constant(lag);
  } else {
    stage.mutable_shift()->set_delay(lag);
  }
  return stage;
}

double joint_lag_search_window(const JointLagStudy& config) {
  if (config.max_lag_search() > 0.0) return config.max_lag_search();
  double largest = 0.0;
  for (const double r : config.network_round_trips()) {
    for (const double a : config.actuator_lags()) largest = std::max(largest, r + a);
  }
  return 2.0 * largest + 0.01;
}

void fill_joint_lag_errors(JointLagPoint& point, const std::vector<double>& reference,
                           const std::vector<double>& u, bool stopped_early, double dt,
                           double growth_period) {
  const Comparison c = compare(reference, u, stopped_early);
  point.peak_error_pct = c.peak_error_pct;
  point.rms_error_pct = c.rms_error_pct;
  point.nrmse = c.nrmse_pct / 100.0;
  point.paper_eq2 = c.paper_eq2_as_printed;
  point.peak_error = c.peak_error_m;
  point.diverged = c.diverged || diverging(u, dt, growth_period, point.past_boundary);
}

JointLagStudy load_joint_lag(const std::filesystem::path& path) {
  JointLagStudy config;
  study::parse_text_format(study::read_text_file(path, "joint lag config"), path.string(), config);
  const auto source = path.string();
  if (config.study().empty()) throw std::invalid_argument(source + ": study is empty");
  check_lags(config.network_round_trips(), "network_round_trips", source, true);
  check_lags(config.actuator_lags(), "actuator_lags", source, true);
  check_lags(config.measured_network_round_trips(), "measured_network_round_trips", source, false);
  check_lags(config.measured_actuator_lags(), "measured_actuator_lags", source, false);
  if (config.max_lag_search() < 0.0 || config.measured_duration() < 0.0) {
    throw std::invalid_argument(source + ": max_lag_search and measured_duration must be >= 0");
  }
  return config;
}

namespace {

// Before the grid runs: how many of its points lie past the stability boundary, as a warning.
void warn_past_boundary(const JointLagStudy& config,
                        const std::map<double, std::optional<double>>& critical_at,
                        const JointLagOptions& options) {
  int past = 0, total = 0;
  for (const double r : config.network_round_trips())
    for (const double a : config.actuator_lags()) {
      ++total;
      const auto it = critical_at.find(a);
      past += it != critical_at.end() && it->second && r >= *it->second ? 1 : 0;
    }
  if (past == 0) return;
  const std::string warning =
      std::to_string(past) + " of " + std::to_string(total) +
      " grid points lie past the stability boundary (network round trip beyond the critical "
      "one for their actuator lag): they are expected to diverge";
  if (options.warn)
    options.warn(warning);
  else
    spdlog::warn("{}", warning);
}

// Why the across-sites part does not run, or empty when it does.
std::string why_not_across_sites(const JointLagStudy& config, const JointLagOptions& options) {
  if (config.sites().empty() || config.measured_network_round_trips().empty() ||
      config.measured_actuator_lags().empty())
    return "the config asks for no across-sites runs";
  if (!options.measure) return "across-sites runs not requested (--no-measure)";
  if (!options.across_sites.unavailable || !options.across_sites.run)
    return "this program cannot run across sites (no across-sites runner)";
  if (const auto reason = options.across_sites.unavailable()) return *reason;
  return "";
}

// What every in-process grid point shares: the prepared study, its reference response, each
// actuator lag's critical round trip (s) and the J1 search window (s).
struct GridInputs {
  const JointLagStudy& config;
  const study::PreparedStudy& prepared;
  const std::vector<double>& reference_response;
  const std::map<double, std::optional<double>>& critical_at;
  double window = 0.0;
};

// One in-process point: the study run with a network shift of `round_trip` (s) then the
// actuator model at `actuator` (s), judged against the reference.
JointLagPoint run_grid_point(const GridInputs& grid, double round_trip, double actuator) {
  const study::PreparedStudy& prepared = grid.prepared;
  config::Case joint;
  joint.set_name("joint");
  joint.add_delay()->mutable_shift()->set_delay(round_trip);
  *joint.add_delay() = joint_lag_actuator_stage(grid.config.actuator_model(), actuator);
  if (grid.config.has_force_predictor())
    *joint.mutable_force_predictor() = grid.config.force_predictor();
  const auto run = core::simulate(study::setup_for_case(prepared, joint), prepared.motion);
  JointLagPoint point;
  point.network_round_trip = round_trip;
  point.actuator_lag = actuator;
  if (const auto it = grid.critical_at.find(actuator); it != grid.critical_at.end() && it->second)
    point.past_boundary = round_trip >= *it->second;
  // The growth is fitted at the governing mode's period, as `rths run` fits it.
  const auto check =
      point.past_boundary ? check_case_critical_delay(prepared, joint, 0.0) : std::nullopt;
  fill_joint_lag_errors(point, grid.reference_response, floor_history(run, 0), run.diverged,
                        prepared.base.dt, check ? check->governing_period : 0.0);
  if (!point.diverged) {
    point.measured_total_lag = core::j1_delay(column_of(run.command, 0), column_of(run.realised, 0),
                                              prepared.base.dt, grid.window);
  }
  return point;
}

}  // namespace

JointLagResult run_joint_lag(const JointLagStudy& config, const std::filesystem::path& base_dir,
                             const JointLagOptions& options) {
  JointLagResult result;
  const auto study = study::load_study(base_dir / config.study());
  result.study_name = study.name();
  result.actuator_model = model_name(config.actuator_model());
  result.output_directory = options.output_directory ? *options.output_directory
                            : config.output_directory().empty()
                                ? std::filesystem::path("out/joint_lag")
                                : std::filesystem::path(config.output_directory());
  std::filesystem::create_directories(result.output_directory);

  const auto study_dir = (base_dir / config.study()).parent_path();
  const auto prepared = study::prepare_study(study, study_dir);
  const auto reference = core::simulate(
      study::setup_for_case(prepared, study::reference_case(study)), prepared.motion);
  const auto u_ref = floor_history(reference, 0);
  const double window = joint_lag_search_window(config);
  fill_boundary(config, prepared, result);
  fill_compensated_boundary(config, prepared, result);
  std::map<double, std::optional<double>> critical_at;  // actuator lag -> critical round trip
  if (result.boundary_skipped.empty() || !result.compensated_boundary.empty())
    for (const double a : config.actuator_lags())
      critical_at[a] = critical_round_trip_at(config, prepared, a);
  warn_past_boundary(config, critical_at, options);
  result.measured_skipped = why_not_across_sites(config, options);
  const std::size_t total =
      static_cast<std::size_t>(config.network_round_trips_size() * config.actuator_lags_size()) +
      (result.measured_skipped.empty()
           ? static_cast<std::size_t>(config.measured_network_round_trips_size() *
                                      config.measured_actuator_lags_size())
           : 0);
  std::size_t done = 0;
  const std::function<void()> one_done = [&] {
    if (options.progress) options.progress(++done, total);
  };
  const GridInputs grid{config, prepared, u_ref, critical_at, window};
  for (const double round_trip : config.network_round_trips()) {
    for (const double actuator : config.actuator_lags()) {
      result.grid.push_back(run_grid_point(grid, round_trip, actuator));
      one_done();
    }
  }

  if (result.measured_skipped.empty()) options.across_sites.run(config, base_dir, result, one_done);
  return result;
}

void write_joint_lag_outputs(const JointLagResult& result, bool plots) {
  const auto& out = result.output_directory;
  write_csv(result.grid, out / "grid.csv");
  write_csv(result.measured, out / "measured.csv");
  {
    std::ofstream json(out / "summary.json");
    json << to_json(result).dump(2) << "\n";
  }
  if (plots) {
    write_error_map(result, out);
    write_total_lag_png(result, out);
  }
}

nlohmann::json to_json(const JointLagResult& result) {
  nlohmann::json grid = nlohmann::json::array(), measured = nlohmann::json::array();
  for (const auto& p : result.grid) grid.push_back(point_json(p));
  for (const auto& p : result.measured) measured.push_back(point_json(p));
  const auto boundary_json = [](const std::vector<BoundaryPoint>& points) {
    nlohmann::json out = nlohmann::json::array();
    for (const auto& b : points)
      out.push_back(
          {{"actuator_lag_s", b.actuator_lag},
           {"critical_network_round_trip_s",
            b.critical_round_trip ? nlohmann::json(*b.critical_round_trip) : nlohmann::json()}});
    return out;
  };
  nlohmann::json out = {{"study", result.study_name},
                        {"actuator_model", result.actuator_model},
                        {"output_directory", result.output_directory.string()},
                        {"grid", grid},
                        {"measured", measured},
                        {"measured_skipped", result.measured_skipped},
                        {"stability_boundary", boundary_json(result.boundary)},
                        {"stability_boundary_skipped", result.boundary_skipped}};
  if (!result.compensated_boundary_note.empty()) {
    out["compensated_stability_boundary"] = boundary_json(result.compensated_boundary);
    out["compensated_stability_boundary_note"] = result.compensated_boundary_note;
  }
  return out;
}

std::size_t diverged_points(const JointLagResult& result) {
  const auto diverged = [](const JointLagPoint& p) { return p.diverged; };
  return static_cast<std::size_t>(
      std::count_if(result.grid.begin(), result.grid.end(), diverged) +
      std::count_if(result.measured.begin(), result.measured.end(), diverged));
}

std::string to_text(const JointLagResult& result) {
  std::ostringstream out;
  out.setf(std::ios::fixed);
  out.precision(2);
  out << "joint lag study of " << result.study_name << " (actuator " << result.actuator_model
      << "): E_rms % [measured total lag ms]\n";
  out << "  network RT \\ actuator";
  std::vector<double> actuators;
  for (const auto& p : result.grid) {
    if (std::find(actuators.begin(), actuators.end(), p.actuator_lag) == actuators.end()) {
      actuators.push_back(p.actuator_lag);
    }
  }
  for (const double a : actuators) out << "  " << std::setw(14) << a * 1e3 << " ms";
  double previous = std::nan("");
  for (const auto& p : result.grid) {
    if (p.network_round_trip != previous) {
      out << "\n  " << std::setw(10) << p.network_round_trip * 1e3 << " ms         ";
      previous = p.network_round_trip;
    }
    if (p.diverged) {
      out << "  " << std::setw(17) << "diverged";
    } else {
      out << "  " << std::setw(17)
          << fmt::format("{:.2f} [{:.2f}]", p.rms_error_pct, p.measured_total_lag * 1e3);
    }
  }
  out << "\n";
  if (!result.compensated_boundary_note.empty())
    out << "every grid point runs with a force predictor; " << result.compensated_boundary_note
        << "\n";
  if (result.measured.empty()) {
    out << "across sites: skipped (" << result.measured_skipped << ")\n";
  }
  for (const auto& p : result.measured) {
    out << "across sites (" << (p.real_time ? "real time" : "lockstep") << "): injected "
        << p.network_round_trip * 1e3 << " ms network + " << p.actuator_lag * 1e3
        << " ms actuator = " << (p.network_round_trip + p.actuator_lag) * 1e3
        << " ms; measured total " << p.measured_total_lag * 1e3 << " ms = round trip "
        << p.measured_round_trip * 1e3 << " ms + actuator " << p.measured_actuator_lag * 1e3
        << " ms; E_rms " << p.rms_error_pct << " % over the first " << p.duration << " s against "
        << p.in_process_rms_error_pct << " % in process for "
        << (p.real_time ? "the same lags" : "the actuator lag alone") << " over the same "
        << p.duration << " s" << (p.diverged ? " (diverged)" : "") << "\n";
    if (!p.real_time && p.network_round_trip > 0.0)
      out << "  lockstep waits for every answer, so the " << p.network_round_trip * 1e3
          << " ms network round trip delays the exchange in wall-clock time only and never "
             "reaches the response: this run checks the distributed machinery, not the map's "
             "network axis (a sites config with clock: REAL_TIME measures that)\n";
  }
  out << "written: " << (result.output_directory / "grid.csv").string()
      << ", error_map.png/.svg, total_lag.png/.svg, summary.json\n";
  return out.str();
}

}  // namespace rths::analysis
