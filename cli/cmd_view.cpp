// rths view RECORD: serves the live view's page over a finished (or truncated) run record, with a
// time slider, until Ctrl-C (or --for SECONDS). The record is read whole (runtime::read_record,
// which keeps every complete entry of a cut record and says where it was cut) and fed through the
// same view::Feed a running coordinator feeds, so the page shows a record as it showed the run.
// Exit: 2 a record that cannot be read or a bad --listen; 3 the address cannot be bound.
#include <chrono>
#include <iostream>
#include <thread>

#include "cli/commands.h"
#include "cli/support.h"
#include "runtime/record/record.h"
#include "util/process.h"
#include "view/context.h"
#include "view/feed.h"
#include "view/server.h"

namespace rths::cli {
namespace {

struct ViewArgs {
  std::string record, listen = "127.0.0.1:8080";
  double seconds = 0;  // 0: until Ctrl-C
};

void run_view(const ViewArgs& args) {
  view::ListenAddress address;
  runtime::RecordContents contents;
  try {
    address = view::parse_listen_address(args.listen, "--listen");
    contents = runtime::read_record(args.record);
  } catch (const std::exception& e) {
    throw ExitError(kExitBadInput, e.what());
  }
  if (!contents.header())
    throw ExitError(kExitBadInput, args.record + ": no run header: not a run record");
  view::Feed feed;
  // The critical delay and the in-process prediction from the record's study (relative paths
  // beside the record; the record's own motion when the study's file is not here), before the
  // steps, which then carry it.
  view::describe_record(feed, contents, std::filesystem::path(args.record).parent_path());
  for (const auto& entry : contents.entries) feed.add(entry);
  feed.finish();
  view::ServerOptions options;
  options.address = address;
  options.mode = "replay";
  std::unique_ptr<view::ViewServer> server;
  util::HeldStopSignals signals;
  try {
    server = std::make_unique<view::ViewServer>(feed, options);
  } catch (const std::exception& e) {
    throw ExitError(kExitEnvironment, e.what());
  }
  std::cout << "rths view: " << args.record << " (" << feed.steps_seen() << " steps"
            << (contents.truncated ? ", cut short" : "") << ") at " << server->url()
            << "  (Ctrl-C to stop)" << std::endl;
  const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(args.seconds);
  while (!signals.stop_requested() &&
         (args.seconds <= 0 || std::chrono::steady_clock::now() < until))
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  server->shutdown(std::chrono::milliseconds(0));
}

}  // namespace

void add_view_command(CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "view", "Serve the view of a run record in the browser, with a time slider");
  auto args = std::make_shared<ViewArgs>();
  cmd->add_option("record", args->record, "run record (.rthsrec), also one cut short")->required();
  cmd->add_option("--listen", args->listen,
                  "HOST:PORT to serve on (default 127.0.0.1:8080; port 0 = any free)");
  cmd->add_option("--for", args->seconds,
                  "stop serving after this many seconds (default: until Ctrl-C)")
      ->transform(seconds_value());
  cmd->callback([args] { run_view(*args); });
}

}  // namespace rths::cli
