// rths rt-check [CONFIG]: what this machine offers a real-time run and whether a deployment's
// fail-safe windows and max_overrun_fraction will hold on it (rt_check/check.h does the work).
// Without CONFIG it judges the default deployment at --rate for a run of --run-seconds.
// Exit: 0 the deployment holds; 1 it does not (a real-time run would refuse to start); 2 bad
// input; 3 the measurement could not run.
#include <iostream>

#include "cli/commands.h"
#include "cli/support.h"
#include "rt_check/check.h"

namespace rths::cli {
namespace {

struct RtCheckArgs {
  std::string config;
  double seconds = 10, rate = 1024, run_seconds = 60;
  bool json = false;
};

rt_check::PlatformCheck run_check(const RtCheckArgs& args, CLI::App& cmd) {
  if (args.config.empty()) {
    config::Deployment deployment;
    deployment.set_clock(config::Deployment::REAL_TIME);
    return rt_check::check_platform(deployment, 1.0 / args.rate, args.run_seconds, args.seconds);
  }
  for (const char* flag : {"--rate", "--run-seconds"})
    if (cmd.count(flag) > 0)
      throw ExitError(kExitBadInput, std::string(flag) +
                                         " is for the default deployment; with a config, its "
                                         "integrator dt and motion length are used");
  const std::filesystem::path path = args.config;
  const config::Study study = load_config_as<config::Study>(path, "study", study::load_study);
  const study::PreparedStudy prepared = study::prepare_study(study, path.parent_path());
  return rt_check::check_platform(prepared, args.seconds);
}

}  // namespace

void add_rt_check_command(CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "rt-check",
      "Measure this machine's real-time wake-ups and judge a deployment's fail-safe on them");
  auto args = std::make_shared<RtCheckArgs>();
  cmd->add_option("config", args->config, "study config whose deployment is judged (text format)");
  cmd->add_option("--seconds", args->seconds, "s of measurement (default 10)")
      ->check(finite_in(0.1, 3600.0));
  cmd->add_option("--rate", args->rate, "Hz, without a config (default 1024)")
      ->check(finite_in(1.0, 100000.0));
  cmd->add_option("--run-seconds", args->run_seconds,
                  "s of the run judged, without a config (default 60)")
      ->check(finite_in(0.001, 86400.0));
  cmd->add_flag("--json", args->json, "print the report as JSON");
  cmd->callback([args, cmd] {
    rt_check::PlatformCheck check;
    try {
      check = run_check(*args, *cmd);
    } catch (const ExitError&) {
      throw;  // already classified (bad input)
    } catch (const std::runtime_error& e) {
      throw ExitError(kExitEnvironment, std::string("rt-check: ") + e.what());
    }
    if (args->json) {
      nlohmann::json j;
      j["platform"] = rt_check::summary_json(check.summary);
      j["holds"] = !check.verdict.refused();
      j["window_holds"] = check.verdict.window_holds;
      j["overruns_hold"] = check.verdict.overruns_hold;
      j["required_steps"] = check.verdict.required_steps;
      j["false_stop_probability"] = check.verdict.false_stop_probability;
      j["findings"] = check.verdict.findings;
      j["fixes"] = check.verdict.fixes;
      std::cout << j.dump(2) << "\n";
    } else {
      std::cout << rt_check::summary_text(check.summary);
    }
    if (check.verdict.refused())
      throw ExitError(kExitRunFailed,
                      "the deployment's fail-safe or overrun tolerance will not hold "
                      "on this machine (see above)");
  });
}

}  // namespace rths::cli
