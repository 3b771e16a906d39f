#pragma once
// A distributed run across emulated sites on this host (`rths sites CONFIG`).
//
//   load_sites     reads a rths.deploy.Sites config (text format) and the study it names; checks
//                  that every node of the study's deployment (and the coordinator, node 0) is
//                  placed at exactly one site and every link names a node; returns the study with
//                  the sites' overrides applied (domain, case, clock, duration, per-link lag as
//                  each node's receive_lag = to_node and send_lag = from_node).
//   run_sites      builds one network namespace per site (NamespaceTopology), writes a Cyclone DDS
//                  unicast config per site (peers = every site address, interface eth0), then runs
//                  the one launch sequence (runtime::launch_run) with each process placed in its
//                  site's namespace (bounded by the timeout; stop_requested() is polled, e.g. for
//                  Ctrl-C), then deletes every namespace -- on success, failure or exception.
//                  The record is OUT/<case>.rthsrec, as `rths launch` names it.
//                  The coordinator's record is summarised per link: injected lag and measured
//                  round trip / one-way lags (s).
// Errors: std::invalid_argument for bad configs (naming file and field), NamespacesUnavailable
// when this host does not permit namespaces, std::runtime_error for a program that cannot start.

#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "rths/deploy/sites.pb.h"
#include "rths/proto/config.pb.h"
#include "runtime/node/lag.h"

namespace rths::deploy {

struct NodePlacement {
  int node_id = 0;   // 0 = coordinator
  std::string kind;  // "coordinator", "substructure", "actuator_emulator"
  std::string site;
};

struct SitesPlan {
  std::filesystem::path sites_file, study_file;
  Sites sites;
  config::Study study;  // with the overrides applied and relative paths made absolute
  std::vector<NodePlacement> placements;
  double timeout = 300.0;  // s
};

Sites parse_sites(const std::string& text, const std::string& source_name);
SitesPlan load_sites(const std::filesystem::path& sites_file);
// The same checks and overrides for a Sites message built in code (study path relative to
// base_dir).
SitesPlan plan_sites(const Sites& sites, const std::filesystem::path& base_dir,
                     const std::string& source_name);

struct LinkMeasurement {
  int node_id = 0;
  std::string kind, site;
  double configured_to_node = 0.0, configured_from_node = 0.0;  // s, one-way delays asked for
  runtime::LagSummary injected;    // s, what the node reports it injected (receive + send)
  runtime::LagSummary round_trip;  // s, coordinator clock, command sent -> feedback received
  runtime::LagSummary one_way_down, one_way_up;  // s, same host clock here, so meaningful
};

struct SitesRunResult {
  bool ok = false;  // the coordinator exited 0 and the record has a completed footer
  int coordinator_exit = -1;
  std::string status;  // footer status, or why the run stopped
  std::string failed_node;
  std::string run_id, case_name;
  std::filesystem::path output_dir, record;
  std::vector<std::string> namespaces;  // made and removed
  std::vector<LinkMeasurement> links;
  std::int64_t steps = 0;
  double wall_seconds = 0.0;         // whole run as measured here (start-up included)
  double record_wall_seconds = 0.0;  // the coordinator's own run time (footer)
};

struct SitesRunOptions {
  std::filesystem::path output_dir;  // records, logs, DDS configs, merged study; created
  std::optional<std::filesystem::path> bin_dir;  // else util::find_node_programs' search
  std::function<bool()> stop_requested;          // polled every few ms; true = stop now
  // Real time: the platform check already made (`rths rt-check --json` output), handed to the
  // coordinator as `rths launch` hands it; empty: the coordinator measures. accept_platform runs
  // a deployment the check refuses (the record says so).
  std::filesystem::path platform_file;
  bool accept_platform = false;
  double platform_seconds = -1.0;  // the coordinator's own measurement when no file; < 0: default
  std::vector<std::string> coordinator_args;  // appended to the coordinator's (e.g. --view H:P)
};

SitesRunResult run_sites(const SitesPlan& plan, const SitesRunOptions& options);

// Per-link summaries of a record file (coordinator's LinkSamples).
std::vector<LinkMeasurement> measure_links(const std::filesystem::path& record,
                                           const SitesPlan& plan);

// Checks a record written elsewhere (e.g. by the containerised run): it has a footer that says
// completed, at least `min_steps` steps, and every link's median injected lag within 0.1 ms of
// `expected_injected` (s; negative = not checked). Returns the per-link summary as text; throws
// std::runtime_error saying what is wrong.
std::string check_record(const std::filesystem::path& record, std::int64_t min_steps,
                         double expected_injected);

nlohmann::json to_json(const SitesRunResult& result);
std::string to_text(const SitesRunResult& result);

}  // namespace rths::deploy
