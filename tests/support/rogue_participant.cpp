// rths_rogue: a hostile DDS participant for the forgery tests (tests/runtime/forgery_test.cpp).
// It joins a run's domain as a stranger, learns the run id off the wire and attacks:
//
//   rths_rogue --domain D --mode MODE [--every K] [--seconds S]
//
//   answers    as node 1 on node 1's own up topic: for each COMMAND of node 1 it sees whose step
//              is a multiple of --every (1: every step), a FEEDBACK to that step (force 12345 N,
//              echoing the command's stamp: the best forgery a stranger can make).
//   first      as node 1: from the moment it learns the run id (node 1's ASSIGN), a FEEDBACK to
//              step 1 every millisecond until it sees the command of step 1, then an echo of it.
//   takeover   as node 1 before the coordinator pins it: from the moment it learns the run id
//              (node 1's own ANNOUNCE on node 1's up topic, or its ASSIGN), an ANNOUNCE and a
//              READY as node 1 every millisecond, then a FEEDBACK to every COMMAND of node 1.
//   hold       as node 1, from the moment it learns the run id: a HOLD every millisecond.
//   error      as node 1, from the moment it learns the run id: a READY carrying an error.
//   control    never an answer; once the run's commands flow: as the coordinator, HOLD, STOP,
//              ASSIGN and a COMMAND to nodes 1 and 2 on their own command topics, addressed and
//              as a broadcast; as node 2 on its own up topic, HOLD and ANNOUNCE (and an ANNOUNCE
//              with an empty run id); garbage, another run's messages and replays of the commands
//              it saw.
//   replay     never a message of its own: every message of nodes 1 and 2 and of the coordinator
//              to them that it sees, re-published byte for byte, MAC included, from its own
//              writers (rogue_replay.h); prints "replayed <topic> kind K: N" per topic and kind.
// Stops after --seconds, when it sees a STOP addressed to node 1 or 2, or on SIGTERM.
// Prints "run <id>", then "sent <n>" and, per kind, what it sent. Exit 0 when it ran, 3 when DDS
// refused (the reason on stderr), 2 for bad usage. (An insider with a lab certificate is
// tests/security's dds_probe: DDS Security stops it before any message.)
#include <CLI/CLI.hpp>
#include <chrono>
#include <csignal>
#include <iostream>
#include <map>
#include <optional>
#include <thread>

#include "runtime/node/schema.h"
#include "tests/support/rogue_replay.h"
#include "transport/dds_endpoint.h"

namespace {

using namespace rths;

// SIGTERM ends the attack as --seconds would, so what was sent is still printed.
volatile std::sig_atomic_t terminated = 0;
void on_sigterm(int) { terminated = 1; }
using Clock = std::chrono::steady_clock;

struct Rogue {
  std::string mode;
  int every = 100;
  std::string run_id;
  std::map<std::string, long> sent;
  std::vector<transport::Message> seen_commands;  // replayed in control mode
  bool stop = false;
  bool running = false;           // a command of the run was seen
  std::uint64_t coordinator = 0;  // the writer the run id was learned from (not the rogue's own)

  void count(const std::string& what) { ++sent[what]; }
};

transport::Message forged_answer(const std::string& run_id, std::int64_t step,
                                 std::int64_t echo_ns) {
  runtime::Feedback f;
  f.add_force(12345.0);
  f.set_command_received_ns(transport::realtime_ns());
  transport::Message m = runtime::pack(run_id, 1, runtime::FEEDBACK, step, f);
  m.echo_ns = echo_ns;
  return m;
}

// What node 1's (or node 2's) command topic shows: the run id, commands, a STOP.
void observe(Rogue& rogue, const transport::Message& m) {
  if (m.kind == runtime::STOP && m.writer == rogue.coordinator && m.run_id == rogue.run_id)
    rogue.stop = true;
  if (rogue.run_id.empty() && !m.run_id.empty() &&
      (m.kind == runtime::ASSIGN || m.kind == runtime::COMMAND)) {
    rogue.run_id = m.run_id;
    rogue.coordinator = m.writer;
    std::cout << "run " << rogue.run_id << std::endl;
  }
  if (m.kind == runtime::COMMAND && m.run_id == rogue.run_id) rogue.running = true;
  if (m.kind == runtime::COMMAND && rogue.seen_commands.size() < 64)
    rogue.seen_commands.push_back(m);
}

// Node 1's own ANNOUNCE (read off its up topic) gives the run id before anything is assigned.
void observe_announce(Rogue& rogue, const transport::Message& m) {
  if (!rogue.run_id.empty() || m.kind != runtime::ANNOUNCE || m.run_id.empty()) return;
  rogue.run_id = m.run_id;
  std::cout << "run " << rogue.run_id << " (from node 1's announcement)" << std::endl;
}

// One round of the early forgeries (takeover, hold, error) as node 1 on its own up topic.
void attack_early(Rogue& rogue, transport::DdsEndpoint& as_node1) {
  const std::string& run = rogue.run_id;
  if (rogue.mode == "takeover") {
    runtime::Announce announce;
    announce.set_schema_version(runtime::kSchemaVersion);
    announce.set_node_id(1);
    announce.set_kind(config::NodeSpec::SUBSTRUCTURE);
    announce.set_host("rogue");
    as_node1.send(runtime::pack(run, 1, runtime::ANNOUNCE, 0, announce));
    runtime::Ready ready;
    ready.set_node_id(1);
    ready.set_storeys(1);
    as_node1.send(runtime::pack(run, 1, runtime::READY, 0, ready));
    rogue.count("ANNOUNCE + READY as node 1");
  } else if (rogue.mode == "hold") {
    runtime::Hold hold;
    hold.set_reason("forged early hold");
    as_node1.send(runtime::pack(run, 1, runtime::HOLD, 0, hold));
    rogue.count("HOLD as node 1");
  } else {
    runtime::Ready ready;
    ready.set_node_id(1);
    ready.set_error("forged: cannot build");
    as_node1.send(runtime::pack(run, 1, runtime::READY, 0, ready));
    rogue.count("error READY as node 1");
  }
}

bool early_mode(const std::string& mode) {
  return mode == "takeover" || mode == "hold" || mode == "error";
}

void attack_answers(Rogue& rogue, transport::DdsEndpoint& as_node1, const transport::Message& m) {
  if (m.kind != runtime::COMMAND || m.run_id != rogue.run_id) return;
  if (rogue.mode == "hold" || rogue.mode == "error") return;
  const bool first = rogue.mode == "first";
  if ((first && m.step == 1) || (!first && m.step % rogue.every == 0)) {
    as_node1.send(forged_answer(rogue.run_id, m.step, m.sent_ns));
    rogue.count("forged answer");
  }
}

// One round of control forgeries (control mode), none of them an answer.
void attack_control(Rogue& rogue, transport::DdsEndpoint& as_coordinator,
                    transport::DdsEndpoint& as_node2) {
  const std::string& run = rogue.run_id;
  runtime::Hold hold;
  hold.set_reason("forged");
  runtime::Stop stop;
  stop.set_reason("forged");
  runtime::Command command;
  command.set_time(0.5);
  command.add_drift(0.01);
  command.add_drift_velocity(0.1);
  for (int node : {1, 2, transport::kBroadcastId}) {
    as_coordinator.send(runtime::pack(run, node, runtime::HOLD, 1, hold));
    as_coordinator.send(runtime::pack(run, node, runtime::STOP, 1, stop));
    as_coordinator.send(runtime::pack(run, node, runtime::ASSIGN, 0, runtime::Assign{}));
    as_coordinator.send(runtime::pack(run, node, runtime::COMMAND, 1'000'000, command));
    rogue.count("HOLD/STOP/ASSIGN/COMMAND as the coordinator");
  }
  runtime::Announce announce;
  announce.set_node_id(2);
  announce.set_kind(config::NodeSpec::ACTUATOR_EMULATOR);
  as_node2.send(runtime::pack(run, 2, runtime::HOLD, 1, hold));
  as_node2.send(runtime::pack(run, 2, runtime::ANNOUNCE, 0, announce));
  as_node2.send(runtime::pack("", 2, runtime::ANNOUNCE, 0, announce));
  as_node2.send(runtime::pack(run, 1, runtime::HOLD, 1, hold));  // node 1's id on node 2's topic
  auto garbage = runtime::pack(run, 2, runtime::HEARTBEAT, 1, runtime::Heartbeat{});
  garbage.kind = 99;  // no such kind
  garbage.payload = "\xff\xff\xff not protobuf";
  as_node2.send(garbage);
  as_node2.send(runtime::pack("another-run", 2, runtime::HOLD, 1, hold));
  rogue.count("HOLD/ANNOUNCE/garbage/foreign as node 2");
  for (const transport::Message& replay : rogue.seen_commands) {
    as_coordinator.send(replay);
    rogue.count("replayed command");
  }
  rogue.seen_commands.clear();
}

int run(Rogue& rogue, int domain, double seconds) {
  const auto options = [&](bool coordinator, int node) {
    transport::DdsEndpointOptions o;
    o.domain_id = static_cast<std::uint32_t>(domain);
    o.coordinator = coordinator;
    o.node_id = node;
    return o;
  };
  const bool control = rogue.mode == "control";
  const bool early = early_mode(rogue.mode);
  transport::DdsEndpoint watcher(options(false, control ? 2 : 1));
  std::optional<transport::DdsEndpoint> as_coordinator;
  if (control || early) as_coordinator.emplace(options(true, 0));
  if (early) as_coordinator->listen_to(1);  // node 1's announcements: the run id, early
  const auto end = Clock::now() + std::chrono::duration<double>(seconds);
  auto next_round = Clock::now();
  while (Clock::now() < end && !rogue.stop && !terminated) {
    if (auto m = watcher.receive(std::chrono::milliseconds(1))) {
      observe(rogue, *m);
      if (!control) attack_answers(rogue, watcher, *m);
    }
    if (early)
      while (auto m = as_coordinator->receive(std::chrono::nanoseconds(0)))
        observe_announce(rogue, *m);
    if (rogue.run_id.empty()) continue;
    if (early) attack_early(rogue, watcher);
    if (rogue.mode == "first" && !rogue.running) {
      watcher.send(forged_answer(rogue.run_id, 1, 0));
      rogue.count("forged answer");
    }
    if (control && rogue.running && Clock::now() >= next_round) {
      attack_control(rogue, *as_coordinator, watcher);
      next_round = Clock::now() + std::chrono::milliseconds(20);
    }
  }
  long total = 0;
  for (const auto& [what, n] : rogue.sent) {
    std::cout << what << ": " << n << "\n";
    total += n;
  }
  std::cout << "sent " << total << std::endl;
  return 0;
}

int replay(int domain, double seconds) {
  long total = 0;
  for (const auto& [what, n] : rogue::replay(domain, seconds, terminated)) {
    std::cout << "replayed " << what << ": " << n << "\n";
    total += n;
  }
  std::cout << "sent " << total << std::endl;
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"rths_rogue: a hostile participant for the forgery tests"};
  Rogue rogue;
  int domain = -1;
  double seconds = 30;
  app.add_option("--domain", domain)->required();
  app.add_option("--mode", rogue.mode)
      ->required()
      ->check(
          CLI::IsMember({"answers", "first", "takeover", "hold", "error", "control", "replay"}));
  app.add_option("--every", rogue.every)->check(CLI::PositiveNumber);
  app.add_option("--seconds", seconds);
  CLI11_PARSE(app, argc, argv);
  std::signal(SIGTERM, on_sigterm);
  try {
    if (rogue.mode == "replay") return replay(domain, seconds);
    return run(rogue, domain, seconds);
  } catch (const std::exception& e) {
    std::cerr << "rths_rogue: " << e.what() << "\n";
    return 3;
  }
}
