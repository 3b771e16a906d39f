#pragma once
// An OpenSees site: one OpenSees analysis (its genericClient element) drives the study's actuator
// emulators over DDS through the coordinator, which runs without an integrator of its own.
//
//   prepare    load the study; refuse (std::invalid_argument, naming the field) a case with a
//              numerical part (OpenSees holds the numerical model: every storey experimental),
//              a substructure node, an implicit integrator, a bad deployment.opensees mapping.
//   serve      wait for one client (accept_timeout); read its size message within the start-up
//              timeout and refuse a wrong one (nothing has moved: no node was started, no record
//              written); start the deployment's actuator emulators on this host (unless they run
//              elsewhere); run the coordinator with the client's session as its integrator
//              (session.h), which writes the record, judges the fail-safe and, on any stop,
//              HOLDs the emulators, STOPs the nodes and closes the record with the reason;
//              close the client; wait kNodeExitGrace for the nodes, then terminate them.
//   clocks     lockstep: every trial waits for the emulators' answer (step_timeout); real time:
//              the coordinator paces commands at dt (the client waits for its force), and the
//              record measures the lateness the client adds (what OpenSees takes between steps).
//   timeouts   between the client's frames: real time command_watchdog_periods x dt (the
//              emulator would hold on its own then), lockstep step_timeout.
// One client per run: any further connection is accepted and closed at once, logged.

#include <chrono>
#include <filesystem>
#include <memory>
#include <string>

#include "coordinator/coordinator.h"
#include "opensees_site/mapping.h"
#include "opensees_site/tcp_channel.h"
#include "security/run_secret.h"

namespace rths::transport {
struct DdsEndpointOptions;
}

namespace rths::opensees {

struct SiteOptions {
  std::filesystem::path config;
  std::string case_name;          // empty: deployment.case_name, else the reference case
  std::string run_id;             // empty: runtime::make_run_id("<study>-<case>")
  int domain = -1;                // -1: deployment.domain_id
  std::filesystem::path record;   // empty: no record
  std::filesystem::path log_dir;  // the started nodes' logs (node_<id>.log)
  std::filesystem::path
      programs_dir;         // where rths-actuator-emulator is; empty: util::find_program's search
  bool start_nodes = true;  // false: the emulators were started elsewhere
  std::filesystem::path security_dir;  // `rths pki init` directory; empty: the deployment's
  // The run secret when the emulators were started elsewhere (start_nodes false); with
  // start_nodes a fresh one is made and handed to them in their environment.
  security::SecretChoice secret;
  std::chrono::milliseconds accept_timeout{-1};  // < 0: wait for a client forever
};

struct SiteOutcome {
  bool served = false;          // a client's analysis ran (its size message was accepted)
  std::string client;           // "127.0.0.1:40312"
  std::string refusal;          // why the client was refused before the run, if it was
  std::string ending;           // how the client's analysis ended (session.h)
  coordinator::RunOutcome run;  // the coordinator's outcome, when served
  bool ok() const { return served && run.ok; }
};

class Site {
 public:
  // Throws std::invalid_argument for a bad config (naming the field and value).
  explicit Site(SiteOptions options);
  ~Site();
  // Serves one client on `listener`. Throws std::runtime_error when no client came in time, when
  // a node program cannot be found or started.
  SiteOutcome serve(Listener& listener);
  int basic_dofs() const;

 private:
  struct Prepared;
  // The coordinator's run with the client's session as its integrator.
  coordinator::RunOutcome run_session(Connection& client, int frame_size,
                                      const transport::DdsEndpointOptions& dds,
                                      coordinator::CoordinatorOptions options, std::string& ending);
  std::unique_ptr<Prepared> prepared_;
  SiteOptions options_;
};

}  // namespace rths::opensees
