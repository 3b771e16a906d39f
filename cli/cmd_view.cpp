// rths view RECORD: serves the live view's page over a finished (or truncated) run record, with a
// time slider, until Ctrl-C (or --for SECONDS): view::RecordView, which `rths launch --view` also
// serves a run's record with once the run has ended. RECORD may be a run's output folder (a sites
// run's: every site on one time axis, grouped by its sites.json); --compare RUN_B serves both runs
// side by side at /compare, with each one's E_peak and E_rms.
// Exit: 2 a record that cannot be read or a bad --listen; 3 the address cannot be bound.
#include <chrono>
#include <iostream>

#include "cli/commands.h"
#include "cli/support.h"
#include "util/process.h"
#include "view/record_view.h"

namespace rths::cli {
namespace {

struct ViewArgs {
  std::string record, compare, listen = "127.0.0.1:8080";
  double seconds = 0;  // 0: until Ctrl-C
};

void run_view(const ViewArgs& args) {
  view::ListenAddress address;
  try {
    address = view::parse_listen_address(args.listen, "--listen");
  } catch (const std::exception& e) {
    throw ExitError(kExitBadInput, e.what());
  }
  util::HeldStopSignals signals;
  std::unique_ptr<view::RecordView> served;
  try {
    served = args.compare.empty()
                 ? std::make_unique<view::RecordView>(args.record, address)
                 : std::make_unique<view::RecordView>(args.record, args.compare, address);
  } catch (const std::invalid_argument& e) {
    throw ExitError(kExitBadInput, e.what());
  } catch (const std::exception& e) {
    throw ExitError(kExitEnvironment, e.what());
  }
  std::cout << "rths view: " << args.record << " (" << served->steps() << " steps"
            << (served->truncated() ? ", cut short" : "") << ") at " << served->url()
            << (args.compare.empty() ? "" : "compare (beside " + args.compare + ")")
            << "  (Ctrl-C to stop)" << std::endl;
  std::optional<std::chrono::steady_clock::time_point> until;
  if (args.seconds > 0) until = seconds_from_now(args.seconds);
  served->serve_until(until, [&signals] { return signals.stop_requested(); });
}

}  // namespace

void add_view_command(CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "view", "Serve the view of a run record in the browser, with a time slider");
  auto args = std::make_shared<ViewArgs>();
  cmd->add_option("record", args->record,
                  "run record (.rthsrec), also one cut short, or a run's output folder holding one "
                  "(a sites run's: its sites from OUT/sites.json)")
      ->required();
  cmd->add_option("--compare", args->compare,
                  "a second run (record or folder) shown beside the first at /compare, with each "
                  "run's E_peak and E_rms");
  cmd->add_option("--listen", args->listen,
                  "HOST:PORT to serve on (default 127.0.0.1:8080; port 0 = any free)");
  cmd->add_option("--for", args->seconds,
                  "stop serving after this many seconds (default: until Ctrl-C)")
      ->transform(seconds_value());
  cmd->callback([args] { run_view(*args); });
}

}  // namespace rths::cli
