// rths_controller_bench [--steps N]: the wall time one COMMAND takes through a node service, from
// the message handed to it to its FEEDBACK, for the actuator emulator (the actuator computed in
// the node) and for the controller node (a command frame over UDP on 127.0.0.1 to
// rths-controller-emulator, another process running the same actuator, and its answer judged).
// The difference is what a controller node adds to a step before any rig: frames, two UDP hops
// and the other process's wake-up. DDS is left out (it is the same for both). Prints the median
// and p99 of each (us) and of the difference; never a test. The controller node answers on its
// answer thread (the node loop's); the bench runs that thread's two calls in its own loop, so a
// step's time is from the command to its FEEDBACK, as the coordinator would see it.
#include <CLI/CLI.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <thread>

#include "actuator_emulator/actuator_service.h"
#include "bench/bench_support.h"
#include "controller_node/controller_service.h"
#include "runtime/node/plan.h"
#include "runtime/node/schema.h"
#include "util/process.h"

namespace {

using namespace rths;

constexpr const char* kRunId = "controller-bench";
constexpr const char* kLink =
    "controller { local_address: \"127.0.0.1\" local_port: 47220 peer_address: \"127.0.0.1\" "
    "peer_port: 47221 command { fields { role: COUNTER type: U32 } fields { role: STATUS type: "
    "U32 } fields { role: COMMAND_TIME } fields { role: TARGET_DISPLACEMENT } fields { role: "
    "TARGET_VELOCITY } } feedback { fields { role: COUNTER type: U32 } fields { role: STATUS "
    "type: I32 } fields { role: MEASURED_DISPLACEMENT } fields { role: MEASURED_FORCE } } }";

runtime::Assign assign_for(const config::Study& study, const std::filesystem::path& dir) {
  runtime::Assign a;
  a.set_schema_version(runtime::kSchemaVersion);
  *a.mutable_study() = study;
  a.set_base_dir(dir.string());
  a.set_case_name("lag");
  *a.mutable_node() = study.deployment().nodes(0);
  a.set_dt(study.integrator().dt());
  a.add_storeys(0);
  a.add_actuators(0);
  return a;
}

// Wall time (us) of each of `steps` commands handled by `service` (already assigned).
std::vector<double> time_steps(runtime::NodeService& service, int steps, double dt) {
  std::vector<double> us;
  us.reserve(static_cast<std::size_t>(steps));
  runtime::Command command;
  for (int k = 1; k <= steps; ++k) {
    const double t = k * dt;
    command.Clear();
    command.set_time(t);
    command.add_drift(0.01 * std::sin(2 * M_PI * t));
    command.add_drift_velocity(0.02 * M_PI * std::cos(2 * M_PI * t));
    const auto message = runtime::pack(kRunId, service.node_id(), runtime::COMMAND, k, command);
    const auto start = std::chrono::steady_clock::now();
    auto replies = service.handle(message);
    // An asynchronous node (the controller's) answers on its answer thread: the loop it runs.
    const auto give_up = start + std::chrono::seconds(2);
    while (service.asynchronous() && replies.empty() &&
           std::chrono::steady_clock::now() < give_up) {
      service.await_answers(controller_node::monotonic_ns() + 1'000'000);
      service.take_answers([&replies](const transport::Message& m) { replies.push_back(m); });
    }
    const auto end = std::chrono::steady_clock::now();
    if (replies.empty() || replies.front().kind != runtime::FEEDBACK || replies.front().step != k)
      throw std::runtime_error("step " + std::to_string(k) + " not answered");
    us.push_back(std::chrono::duration<double, std::micro>(end - start).count());
  }
  return us;
}

double quantile(std::vector<double> v, double q) {
  std::sort(v.begin(), v.end());
  return v[static_cast<std::size_t>(q * static_cast<double>(v.size() - 1))];
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"rths_controller_bench: a controller node's added time per step"};
  int steps = 20000;
  app.add_option("--steps", steps, "commands timed per node");
  CLI11_PARSE(app, argc, argv);
  const auto dir = std::filesystem::temp_directory_path() / "rths_controller_bench";
  std::filesystem::create_directories(dir);
  const double seconds = steps * 0.001 + 1.0;
  const std::string text = bench::sdof_study_text(
      "controller_bench", 0.001, bench::imperial_valley_motion(seconds),
      std::string("deployment { nodes { id: 2 kind: CONTROLLER ") + kLink + " } }");
  const auto config = dir / "study.textproto";
  std::ofstream(config) << text;
  const config::Study study = study::load_study(config);
  util::ChildProcess emulator(
      std::filesystem::path(RTHS_BINARY_DIR) / "controller_emulator/rths-controller-emulator",
      {"--config", config.string(), "--node-id", "2", "--case", "lag", "--idle-timeout", "10"},
      dir / "controller_emulator.log");
  for (int i = 0; i < 400; ++i) {  // until it listens: a frame sent before is lost
    std::ifstream log(dir / "controller_emulator.log");
    const std::string text_of_log((std::istreambuf_iterator<char>(log)), {});
    if (text_of_log.find("listening on") != std::string::npos) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(25));
  }
  const runtime::Assign assign = assign_for(study, dir);
  const auto assign_message = runtime::pack(kRunId, 2, runtime::ASSIGN, 0, assign);
  actuator_emulator::ActuatorService emulator_node(2, kRunId);
  controller_node::ControllerService controller_node(2, kRunId);
  emulator_node.handle(assign_message);
  controller_node.handle(assign_message);
  const double dt = study.integrator().dt();
  const std::vector<double> local = time_steps(emulator_node, steps, dt);
  const std::vector<double> remote = time_steps(controller_node, steps, dt);
  std::vector<double> added(local.size());
  for (std::size_t i = 0; i < added.size(); ++i) added[i] = remote[i] - local[i];
  std::printf("%d steps each, us per step        median      p99\n", steps);
  std::printf("actuator emulator node          %8.2f %8.2f\n", quantile(local, 0.5),
              quantile(local, 0.99));
  std::printf("controller node + emulator      %8.2f %8.2f\n", quantile(remote, 0.5),
              quantile(remote, 0.99));
  std::printf("added by the controller path    %8.2f %8.2f\n", quantile(added, 0.5),
              quantile(added, 0.99));
  const auto& r = controller_node.report();
  std::printf("link: %llu frames accepted, %llu lost, round trip max %.3f ms\n",
              static_cast<unsigned long long>(r.frames_accepted()),
              static_cast<unsigned long long>(r.lost()), r.round_trip_max() * 1e3);
  emulator.terminate();
  return 0;
}
