#include "deploy/joint_lag.h"

#include <google/protobuf/io/tokenizer.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <sstream>

#include "analysis/plot.h"
#include "core/metrics.h"
#include "core/simulation.h"
#include "core/study.h"
#include "core/text_format.h"
#include "deploy/netns.h"
#include "runtime/process.h"
#include "deploy/sites.h"
#include "runtime/measurements.h"
#include "runtime/record.h"

namespace rths::deploy {

using runtime::run_command;
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

config::DelayStage actuator_stage(JointLagStudy::ActuatorModel model, double lag) {
  config::DelayStage stage;
  if (model == JointLagStudy::FIRST_ORDER && lag > 0.0) {
    stage.mutable_first_order()->set_time_constant(lag);
  } else {
    stage.mutable_shift()->set_delay(lag);
  }
  return stage;
}

std::vector<double> column(const core::Mat& m, int col) {
  std::vector<double> out(static_cast<std::size_t>(m.rows()));
  for (Eigen::Index i = 0; i < m.rows(); ++i) out[static_cast<std::size_t>(i)] = m(i, col);
  return out;
}

std::string model_name(JointLagStudy::ActuatorModel model) {
  return model == JointLagStudy::FIRST_ORDER ? "first_order" : "shift";
}

double search_window(const JointLagStudy& config) {
  if (config.max_lag_search() > 0.0) return config.max_lag_search();
  double largest = 0.0;
  for (const double r : config.network_round_trips()) {
    for (const double a : config.actuator_lags()) largest = std::max(largest, r + a);
  }
  return 2.0 * largest + 0.01;
}

// Error measures of u against the reference over their common length (a diverged run is shorter).
void fill_errors(JointLagPoint& point, const std::vector<double>& reference,
                 const std::vector<double>& u) {
  const std::size_t n = std::min(reference.size(), u.size());
  const std::span<const double> ref(reference.data(), n), got(u.data(), n);
  point.nrmse = core::nrmse(ref, got);
  point.paper_eq2 = core::paper_eq2(ref, got);
  point.peak_error = core::peak_error(ref, got);
}

void run_measured(const JointLagStudy& config, const std::filesystem::path& base_dir,
                  const std::filesystem::path& out, JointLagResult& result) {
  const auto sites_file = base_dir / config.sites();
  const double duration = config.measured_duration() > 0.0 ? config.measured_duration() : 5.0;
  for (const double round_trip : config.measured_network_round_trips()) {
    for (const double actuator : config.measured_actuator_lags()) {
      auto plan = load_sites(sites_file);
      plan.study.mutable_motion()->set_duration(duration);
      auto& deployment = *plan.study.mutable_deployment();
      const bool real_time = deployment.clock() == config::Deployment::REAL_TIME;
      auto* joint_case = plan.study.add_cases();
      joint_case->set_name("joint_actuator");
      *joint_case->add_delay() = actuator_stage(config.actuator_model(), actuator);
      deployment.set_case_name("joint_actuator");
      for (auto& node : *deployment.mutable_nodes()) {
        if (node.kind() != config::NodeSpec::ACTUATOR_EMULATOR) continue;
        // Only the delay: the study's point is the injected round trip, without jitter or loss.
        config::LinkLag lag;
        lag.set_one_way_delay(round_trip / 2);
        *node.mutable_receive_lag() = lag;
        *node.mutable_send_lag() = lag;
      }
      std::ostringstream name;
      name << "measured_R" << round_trip * 1e3 << "ms_A" << actuator * 1e3 << "ms";
      const auto run = run_sites(plan, {out / name.str(), std::nullopt, {}});
      if (!run.ok) throw std::runtime_error("across-sites run " + name.str() + ": " + run.status);

      JointLagPoint point;
      point.network_round_trip = round_trip;
      point.actuator_lag = actuator;
      for (const auto& link : run.links) {
        if (link.kind == "actuator_emulator") point.measured_round_trip = link.round_trip.median;
      }
      const runtime::RunMeasurements measured = runtime::measure_run(runtime::read_record(run.record));
      const core::SimulationResult& steps = measured.steps;
      if (steps.command.cols() == 0 || steps.displacement.cols() == 0)
        throw std::runtime_error("across-sites run " + name.str() + ": record has no actuator");
      const std::vector<double> command = column(steps.command, 0),
                                realised = column(steps.realised, 0),
                                u = column(steps.displacement, 0);
      const double dt = steps.dt;
      if (command.size() < 10 || !(dt > 0.0)) {
        throw std::runtime_error("across-sites run " + name.str() + ": record too short");
      }
      // Real time: the coordinator pairs each command with the newest feedback it has, which
      // answers an older step when the round trip exceeds the wait, so the realised displacement
      // it records lags the command by round trip + actuator lag. Lockstep: each command is
      // paired with its own answer, so J1 sees the actuator alone and the network part is the
      // measured round trip.
      const double j1 = core::j1_delay(command, realised, dt, search_window(config));
      point.measured_total_lag = real_time ? j1 : point.measured_round_trip + j1;
      point.measured_actuator_lag = real_time ? j1 - point.measured_round_trip : j1;
      point.real_time = real_time;
      // The in-process reference over the same duration.
      auto reference_study = plan.study;
      const auto prepared = core::prepare_study(reference_study, base_dir);
      const auto reference = core::simulate(
          core::setup_for_case(prepared, core::reference_case(reference_study)), prepared.motion);
      fill_errors(point, column(reference.displacement, 0), u);
      point.diverged = measured.has_footer && measured.footer.diverged();
      result.measured.push_back(point);
    }
  }
}

// Log z axis (the error spans decades towards instability); zero error is drawn at this floor.
constexpr double kSurfaceFloorPercent = 0.01;

void write_surface_png(const JointLagResult& result, const std::filesystem::path& out) {
  // gnuplot pm3d wants blocks of equal x separated by blank lines: network-major grid as stored.
  const auto data = out / "error_surface.dat";
  {
    std::ofstream file(data);
    file << "# network_round_trip_ms actuator_lag_ms nrmse_percent\n";
    double previous = std::nan("");
    for (const auto& p : result.grid) {
      if (!std::isnan(previous) && p.network_round_trip != previous) file << "\n";
      previous = p.network_round_trip;
      file << p.network_round_trip * 1e3 << ' ' << p.actuator_lag * 1e3 << ' '
           << (p.diverged ? std::nan("") : std::max(100.0 * p.nrmse, kSurfaceFloorPercent))
           << "\n";
    }
  }
  const auto script = out / "error_surface.gp";
  {
    std::ofstream file(script);
    file << "set terminal pngcairo size 1100,800 noenhanced\n"
         << "set output '" << (out / "error_surface.png").string() << "'\n"
         << "set title 'Joint lag study (" << result.study_name << ", actuator "
         << result.actuator_model << "): NRMSE of the displacement, %'\n"
         << "set xlabel 'network round trip (ms)'\nset ylabel 'actuator lag (ms)'\n"
         << "set zlabel 'NRMSE (%), log scale' rotate by 90\n"
         << "set logscale z\nset logscale cb\nset format z '%g'\nset format cb '%g'\n"
         << "set pm3d at s hidden3d\nset palette rgbformulae 33,13,10\n"
         << "set view 55,35\nset contour base\nset cntrparam levels discrete 5,10,20,50,100,1000\n"
         << "unset key\n"
         << "splot '" << data.string() << "' using 1:2:3 with pm3d notitle\n";
  }
  const auto run = run_command({"gnuplot", script.string()}, std::chrono::seconds(60));
  if (!run.ok()) {
    throw std::runtime_error("gnuplot failed on " + script.string() + ": " + run.output);
  }
}

void write_total_lag_png(const JointLagResult& result, const std::filesystem::path& out) {
  analysis::PlotSpec spec;
  spec.title = "Measured total lag vs injected network + actuator lag";
  spec.xlabel = "injected network round trip + actuator lag (ms)";
  spec.ylabel = "measured total lag (ms)";
  analysis::Series emulated{"in-process grid (J1 of realised vs command)", {}, {}, "points pt 7"};
  analysis::Series identity{"measured = injected", {}, {}, "lines dt 2"};
  double largest = 0.0;
  for (const auto& p : result.grid) {
    if (p.diverged) continue;
    emulated.x.push_back((p.network_round_trip + p.actuator_lag) * 1e3);
    emulated.y.push_back(p.measured_total_lag * 1e3);
    largest = std::max({largest, emulated.x.back(), emulated.y.back()});
  }
  spec.series.push_back(emulated);
  if (!result.measured.empty()) {
    analysis::Series sites{"across sites (measured from the record)", {}, {}, "points pt 9 ps 2"};
    for (const auto& p : result.measured) {
      sites.x.push_back((p.network_round_trip + p.actuator_lag) * 1e3);
      sites.y.push_back(p.measured_total_lag * 1e3);
      largest = std::max({largest, sites.x.back(), sites.y.back()});
    }
    spec.series.push_back(sites);
  }
  identity.x = {0.0, largest};
  identity.y = {0.0, largest};
  spec.series.push_back(identity);
  analysis::write_png_plot(spec, out / "total_lag.png");
}

void write_csv(const std::vector<JointLagPoint>& points, const std::filesystem::path& file) {
  std::ofstream out(file);
  out << "network_round_trip_s,actuator_lag_s,injected_total_s,measured_total_s,"
         "measured_round_trip_s,measured_actuator_lag_s,nrmse,paper_eq2,peak_error_m,diverged\n";
  out.precision(10);
  for (const auto& p : points) {
    out << p.network_round_trip << ',' << p.actuator_lag << ','
        << p.network_round_trip + p.actuator_lag << ',' << p.measured_total_lag << ','
        << p.measured_round_trip << ',' << p.measured_actuator_lag << ',' << p.nrmse << ','
        << p.paper_eq2 << ',' << p.peak_error << ',' << (p.diverged ? 1 : 0) << "\n";
  }
  if (!out) throw std::runtime_error("cannot write " + file.string());
}

nlohmann::json point_json(const JointLagPoint& p) {
  return {{"network_round_trip_s", p.network_round_trip},
          {"actuator_lag_s", p.actuator_lag},
          {"injected_total_s", p.network_round_trip + p.actuator_lag},
          {"measured_total_s", p.measured_total_lag},
          {"measured_round_trip_s", p.measured_round_trip},
          {"measured_actuator_lag_s", p.measured_actuator_lag},
          {"nrmse", p.nrmse},
          {"paper_eq2", p.paper_eq2},
          {"peak_error_m", p.peak_error},
          {"diverged", p.diverged},
          {"real_time", p.real_time}};
}

}  // namespace

JointLagStudy load_joint_lag(const std::filesystem::path& path) {
  JointLagStudy config;
  core::parse_text_format(core::read_text_file(path, "joint lag config"), path.string(), config);
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

JointLagResult run_joint_lag(const JointLagStudy& config, const std::filesystem::path& base_dir,
                             const JointLagOptions& options) {
  JointLagResult result;
  const auto study = core::load_study(base_dir / config.study());
  result.study_name = study.name();
  result.actuator_model = model_name(config.actuator_model());
  result.output_directory = options.output_directory ? *options.output_directory
                            : config.output_directory().empty()
                                ? std::filesystem::path("out/joint_lag")
                                : std::filesystem::path(config.output_directory());
  std::filesystem::create_directories(result.output_directory);

  const auto study_dir = (base_dir / config.study()).parent_path();
  const auto prepared = core::prepare_study(study, study_dir);
  const auto reference =
      core::simulate(core::setup_for_case(prepared, core::reference_case(study)), prepared.motion);
  const auto u_ref = column(reference.displacement, 0);
  const double window = search_window(config);
  for (const double round_trip : config.network_round_trips()) {
    for (const double actuator : config.actuator_lags()) {
      config::Case joint;
      joint.set_name("joint");
      joint.add_delay()->mutable_shift()->set_delay(round_trip);
      *joint.add_delay() = actuator_stage(config.actuator_model(), actuator);
      const auto run = core::simulate(core::setup_for_case(prepared, joint), prepared.motion);
      JointLagPoint point;
      point.network_round_trip = round_trip;
      point.actuator_lag = actuator;
      point.diverged = run.diverged;
      fill_errors(point, u_ref, column(run.displacement, 0));
      if (!run.diverged) {
        point.measured_total_lag =
            core::j1_delay(column(run.command, 0), column(run.realised, 0), prepared.base.dt, window);
      }
      result.grid.push_back(point);
    }
  }

  if (config.sites().empty() || config.measured_network_round_trips().empty() ||
      config.measured_actuator_lags().empty()) {
    result.measured_skipped = "the config asks for no across-sites runs";
  } else if (!options.measure) {
    result.measured_skipped = "across-sites runs not requested (--no-measure)";
  } else if (const auto reason = namespace_support()) {
    result.measured_skipped = *reason;
  } else {
    run_measured(config, base_dir, result.output_directory, result);
  }
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
    write_surface_png(result, out);
    write_total_lag_png(result, out);
  }
}

nlohmann::json to_json(const JointLagResult& result) {
  nlohmann::json grid = nlohmann::json::array(), measured = nlohmann::json::array();
  for (const auto& p : result.grid) grid.push_back(point_json(p));
  for (const auto& p : result.measured) measured.push_back(point_json(p));
  return {{"study", result.study_name},
          {"actuator_model", result.actuator_model},
          {"output_directory", result.output_directory.string()},
          {"grid", grid},
          {"measured", measured},
          {"measured_skipped", result.measured_skipped}};
}

std::string to_text(const JointLagResult& result) {
  std::ostringstream out;
  out.setf(std::ios::fixed);
  out.precision(2);
  out << "joint lag study of " << result.study_name << " (actuator " << result.actuator_model
      << "): NRMSE % [measured total lag ms]\n";
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
      std::ostringstream cell;
      cell.setf(std::ios::fixed);
      cell.precision(2);
      cell << 100 * p.nrmse << " [" << p.measured_total_lag * 1e3 << "]";
      out << "  " << std::setw(17) << cell.str();
    }
  }
  out << "\n";
  if (result.measured.empty()) {
    out << "across sites: skipped (" << result.measured_skipped << ")\n";
  }
  for (const auto& p : result.measured) {
    out << "across sites (" << (p.real_time ? "real time" : "lockstep") << "): injected " << p.network_round_trip * 1e3 << " ms network + "
        << p.actuator_lag * 1e3 << " ms actuator = " << (p.network_round_trip + p.actuator_lag) * 1e3
        << " ms; measured total " << p.measured_total_lag * 1e3 << " ms = round trip " << p.measured_round_trip * 1e3 << " ms + actuator "
        << p.measured_actuator_lag * 1e3
        << " ms; NRMSE " << 100 * p.nrmse << " %\n";
  }
  out << "written: " << (result.output_directory / "grid.csv").string()
      << ", error_surface.png, total_lag.png, summary.json\n";
  return out.str();
}

}  // namespace rths::deploy
