// rths-controller-emulator: stands in for a lab's real-time controller (controller_emulator.h).
//   rths-controller-emulator --config STUDY --node-id N [--case NAME] [--answer-frames K]
//                            [--idle-timeout S] [--answer-lag-ms MS] [--answer-period-ms MS]
// Exit: 0 after a STOP frame, 1 when no frame came for the idle timeout, 2 bad usage or config.
#include <spdlog/spdlog.h>
#include <CLI/CLI.hpp>

#include "controller_emulator/controller_emulator.h"
#include "runtime/node/node_main.h"
#include "study/study.h"

int main(int argc, char** argv) {
  CLI::App app{"rths-controller-emulator: a lab's real-time controller, emulated over UDP frames"};
  std::string config, case_name;
  int node_id = 0;
  std::int64_t answer_frames = -1;
  double idle_timeout = 30.0, answer_lag_ms = 0.0, answer_period_ms = 0.0;
  app.add_option("--config", config, "the study whose deployment names the CONTROLLER node")
      ->required();
  app.add_option("--node-id", node_id, "the CONTROLLER node it answers")->required();
  app.add_option("--case", case_name, "the case whose actuators it runs (default: reference)");
  app.add_option("--answer-frames", answer_frames,
                 "answer this many command frames, then go silent (a fault drill)");
  app.add_option("--idle-timeout", idle_timeout, "s without a frame before it leaves (exit 1)")
      ->check(rths::runtime::finite_in(0.0, 86400.0));
  app.add_option("--answer-lag-ms", answer_lag_ms,
                 "each answer leaves this many ms after its frame arrived (an injected link lag)")
      ->check(rths::runtime::finite_in(0.0, 60000.0));
  app.add_option("--answer-period-ms", answer_period_ms,
                 "answer at most one frame per this many ms, in order: a controller slower than "
                 "the host, which falls behind (a fault drill)")
      ->check(rths::runtime::finite_in(0.0, 60000.0));
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;  // bad usage is exit 2, as the header says
  }
  try {
    const std::filesystem::path path = std::filesystem::absolute(config);
    rths::controller_emulator::ControllerEmulator emulator(
        rths::study::load_study(path), path.parent_path(), case_name, node_id, answer_frames);
    return rths::controller_emulator::serve(emulator, idle_timeout, answer_lag_ms * 1e-3,
                                            answer_period_ms * 1e-3);
  } catch (const std::exception& e) {
    spdlog::error("rths-controller-emulator: {}", e.what());
    return 2;
  }
}
