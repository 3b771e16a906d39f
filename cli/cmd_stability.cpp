// `rths stability`: the critical delay of a delayed SDOF hybrid system, continuous and discrete.
#include <nlohmann/json.hpp>

#include <iostream>
#include <memory>
#include <numbers>

#include "cli/commands.h"
#include "cli/support.h"
#include "core/stability.h"

namespace rths::cli {
namespace {

struct StabilityOptions {
  double period = 0.5, zeta = 0.05, alpha = 1.0, dt = 0.001;
  std::string integrator = "explicit-newmark";
  int branches = 3, max_steps = 200;
  bool json = false;
};

void run_stability(const StabilityOptions& o) {
  const auto kind = core::integrator_from_string(o.integrator);
  // Beyond the integrator's own limit every delay is unstable, so "first unstable delay = 0
  // steps" would answer the wrong question: refuse the input instead.
  core::check_stability(kind, 2.0 * std::numbers::pi / o.period, o.dt, false);
  const core::ContinuousStability continuous =
      core::continuous_critical_delay(o.period, o.zeta, o.alpha, o.branches);
  const core::DiscreteStability discrete =
      core::discrete_critical_delay(kind, o.period, o.zeta, o.alpha, o.dt, o.max_steps);
  if (o.json) {
    nlohmann::json out;
    out["input"] = {{"period_s", o.period}, {"zeta", o.zeta}, {"experimental_fraction", o.alpha},
                    {"integrator", core::to_string(kind)}, {"dt_s", o.dt}};
    nlohmann::json crossings = nlohmann::json::array();
    for (const auto& c : continuous.crossings) {
      crossings.push_back({{"crossing_omega_rad_per_s", c.omega}, {"delay_s", c.delay}, {"branch", c.branch}});
    }
    out["continuous"] = {{"stable_without_delay", continuous.stable_without_delay},
                         {"stable_for_all_delays", continuous.stable_for_all_delays},
                         {"critical_delay_s", continuous.critical_delay ? nlohmann::json(*continuous.critical_delay) : nlohmann::json()},
                         {"crossings", crossings}};
    out["discrete"] = {
        {"first_unstable_delay_steps", discrete.first_unstable_steps ? nlohmann::json(*discrete.first_unstable_steps) : nlohmann::json()},
        {"first_unstable_delay_s", discrete.first_unstable_delay ? nlohmann::json(*discrete.first_unstable_delay) : nlohmann::json()},
        {"searched_up_to_steps", o.max_steps},
        {"spectral_radius_at_first_unstable", discrete.spectral_radius.empty() ? nlohmann::json() : nlohmann::json(discrete.spectral_radius.back())}};
    std::cout << out.dump(2) << "\n";
    return;
  }
  std::cout << "SDOF T = " << o.period << " s, zeta = " << o.zeta << ", experimental fraction = " << o.alpha << "\n";
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
    std::cout << core::to_string(kind) << ", dt = " << o.dt * 1e3 << " ms: first unstable delay = "
              << *discrete.first_unstable_steps << " steps (" << *discrete.first_unstable_delay * 1e3
              << " ms), spectral radius " << discrete.spectral_radius.back() << "\n";
  } else {
    std::cout << core::to_string(kind) << ", dt = " << o.dt * 1e3 << " ms: stable up to "
              << o.max_steps << " steps of delay\n";
  }
}

}  // namespace

void add_stability_command(CLI::App& app) {
  auto options = std::make_shared<StabilityOptions>();
  CLI::App* cmd = app.add_subcommand("stability", "Critical delay of a delayed SDOF hybrid system");
  cmd->add_option("--period", options->period, "natural period T (s)")->check(CLI::PositiveNumber);
  cmd->add_option("--zeta", options->zeta, "damping ratio")->check(CLI::Range(0.0, 1.0));
  cmd->add_option("--exp-fraction", options->alpha, "experimental fraction alpha of the stiffness")
      ->check(CLI::Range(0.0, 1.0));
  cmd->add_option("--dt", options->dt, "integration step (s, or 1ms); exit 2 beyond the integrator's limit")
      ->transform(seconds_value())
      ->check(CLI::PositiveNumber);
  cmd->add_option("--integrator", options->integrator,
                  "explicit-newmark | central-difference | chen-ricles | newmark-average-acceleration");
  cmd->add_option("--branches", options->branches, "delay branches listed per crossing frequency")
      ->check(CLI::Range(1, 100));
  cmd->add_option("--max-steps", options->max_steps, "largest delay (steps) searched")->check(CLI::Range(0, 5000));
  cmd->add_flag("--json", options->json, "print JSON");
  cmd->callback([options] { run_stability(*options); });
}

}  // namespace rths::cli
