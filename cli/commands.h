#pragma once
// Subcommands of the `rths` command line. Each add_* registers one subcommand on the app; its
// callback throws rths::cli::ExitError to leave with a specific exit code.
//
// Exit codes (stable, for scripts):
//   0  success
//   1  the run completed but failed its purpose (a node died, a limit tripped, a test aborted)
//   2  bad input: usage, config, data file, or a dt beyond the integrator's limit
//   3  internal or environment error (cannot write output, missing tool, namespaces not permitted)

#include <CLI/CLI.hpp>
#include <stdexcept>
#include <string>

namespace rths::cli {

inline constexpr int kExitOk = 0;
inline constexpr int kExitRunFailed = 1;
inline constexpr int kExitBadInput = 2;
inline constexpr int kExitEnvironment = 3;

struct ExitError : std::runtime_error {
  ExitError(int code, const std::string& message) : std::runtime_error(message), code(code) {}
  int code;
};

void add_sdof_command(CLI::App& app);
void add_run_command(CLI::App& app);
void add_stability_command(CLI::App& app);
void add_sweep_command(CLI::App& app);
void add_sites_command(CLI::App& app);
void add_joint_lag_command(CLI::App& app);
void add_identify_command(CLI::App& app);
void add_launch_command(CLI::App& app);
void add_export_command(CLI::App& app);
void add_pki_command(CLI::App& app);
void add_opensees_site_command(CLI::App& app);
void add_view_command(CLI::App& app);

}  // namespace rths::cli
