// rths: the command line. Thin: parses, dispatches to a subcommand, maps errors to exit codes.
#include <spdlog/spdlog.h>

#include <exception>
#include <iostream>

#include "cli/commands.h"
#include "cli/support.h"

int main(int argc, char** argv) {
  CLI::App app{"rths: real-time hybrid simulation with actuator and network lag"};
  app.require_subcommand(1);
  app.set_version_flag("--version", "rths 0.1.0");
  rths::cli::add_sdof_command(app);
  rths::cli::add_run_command(app);
  rths::cli::add_stability_command(app);
  rths::cli::add_sweep_command(app);
  rths::cli::add_sites_command(app);
  rths::cli::add_joint_lag_command(app);
  rths::cli::add_identify_command(app);
  rths::cli::add_launch_command(app);
  rths::cli::add_export_command(app);
  rths::cli::add_pki_command(app);
  rths::cli::add_rt_check_command(app);
  rths::cli::add_opensees_site_command(app);
  rths::cli::add_view_command(app);
  if (const std::string unknown = rths::cli::suggest_for_unknown(app, argc, argv);
      !unknown.empty()) {
    std::cerr << "rths: " << unknown << "\n";
    return rths::cli::kExitBadInput;
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);
    return code == 0 ? 0 : rths::cli::kExitBadInput;
  } catch (const rths::cli::ExitError& e) {
    std::cerr << "rths: " << e.what() << "\n";
    return e.code;
  } catch (const std::invalid_argument& e) {
    std::cerr << "rths: " << e.what() << "\n";
    return rths::cli::kExitBadInput;
  } catch (const std::exception& e) {
    std::cerr << "rths: " << e.what() << "\n";
    return rths::cli::kExitEnvironment;
  }
  return rths::cli::kExitOk;
}
