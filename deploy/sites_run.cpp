// run_sites: topology, DDS configs, processes, wait, record summary; everything undone on exit.
#include <google/protobuf/text_format.h>
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <chrono>
#include <fstream>
#include <map>
#include <memory>
#include <sstream>

#include "deploy/dds_config.h"
#include "deploy/netns.h"
#include "deploy/process.h"
#include "deploy/sites.h"
#include "runtime/measurements.h"
#include "runtime/record.h"
#include "security/check.h"

namespace rths::deploy {
namespace {

constexpr auto kNodeExitGrace = std::chrono::seconds(5);  // after the coordinator, for STOP

std::filesystem::path self_directory() {
  std::error_code error;
  const auto exe = std::filesystem::read_symlink("/proc/self/exe", error);
  return error ? std::filesystem::current_path() : exe.parent_path();
}

std::optional<std::filesystem::path> find_in(const std::vector<std::filesystem::path>& dirs,
                                             const std::string& program) {
  for (const auto& dir : dirs) {
    const auto candidate = dir / program;
    if (::access(candidate.c_str(), X_OK) == 0) return std::filesystem::absolute(candidate);
  }
  return std::nullopt;
}

std::string make_run_id() {
  const auto now = std::chrono::system_clock::now().time_since_epoch();
  return "sites-" + std::to_string(::getpid()) + "-" +
         std::to_string(std::chrono::duration_cast<std::chrono::milliseconds>(now).count());
}

}  // namespace

ProgramPaths find_programs(const std::optional<std::filesystem::path>& bin_dir) {
  std::vector<std::filesystem::path> dirs;
  if (bin_dir) {
    dirs.push_back(*bin_dir);
  } else {
    if (const char* env = std::getenv("RTHS_BIN_DIR"); env != nullptr && *env != '\0') {
      dirs.emplace_back(env);
    }
    const auto self = self_directory();
    // Installed side by side, or the build tree: <build>/cli/rths, <build>/tests/deploy/...
    for (const auto& base : {self, self.parent_path(), self.parent_path().parent_path()}) {
      dirs.push_back(base);
      for (const char* folder : {"coordinator", "substructure_nodes", "actuator_emulator"}) {
        dirs.push_back(base / folder);
      }
    }
#ifdef RTHS_DEPLOY_BINARY_DIR
    for (const char* folder : {"coordinator", "substructure_nodes", "actuator_emulator"}) {
      dirs.push_back(std::filesystem::path(RTHS_DEPLOY_BINARY_DIR) / folder);
    }
#endif
    const char* path = std::getenv("PATH");
    std::stringstream entries(path != nullptr ? path : "");
    std::string entry;
    while (std::getline(entries, entry, ':')) {
      if (!entry.empty()) dirs.emplace_back(entry);
    }
  }
  ProgramPaths paths;
  const std::pair<std::filesystem::path*, const char*> wanted[] = {
      {&paths.coordinator, "rths-coordinator"},
      {&paths.substructure, "rths-substructure-node"},
      {&paths.actuator_emulator, "rths-actuator-emulator"}};
  for (const auto& [slot, program] : wanted) {
    const auto found = find_in(dirs, program);
    if (!found) {
      throw std::runtime_error(std::string("cannot find the program ") + program +
                               (bin_dir ? " in " + bin_dir->string()
                                        : " (set RTHS_BIN_DIR or --bin-dir, or build it)"));
    }
    *slot = *found;
  }
  return paths;
}

SitesRunResult run_sites(const SitesPlan& plan, const SitesRunOptions& options) {
  const auto started = std::chrono::steady_clock::now();
  const auto programs = find_programs(options.bin_dir);
  // DDS Security: every process's documents are checked before anything is built or started.
  const std::filesystem::path security_dir = plan.study.deployment().security_dir();
  if (!security_dir.empty()) {
    std::vector<int> ids;
    for (const auto& placement : plan.placements) ids.push_back(placement.node_id);
    security::check_lab_security(security_dir, ids);
  }
  SitesRunResult result;
  result.output_dir = std::filesystem::absolute(options.output_dir);
  std::filesystem::create_directories(result.output_dir);
  result.record = result.output_dir / "record.pb";
  std::filesystem::remove(result.record);

  const auto study_path = result.output_dir / "study.textproto";
  {
    std::string text;
    google::protobuf::TextFormat::PrintToString(plan.study, &text);
    std::ofstream out(study_path);
    out << "# Written by `rths sites` from " << plan.study_file.string() << " and "
        << plan.sites_file.string() << "\n" << text;
    if (!out) throw std::runtime_error("cannot write " + study_path.string());
  }

  TopologySpec spec;
  for (const auto& site : plan.sites.sites()) spec.sites.push_back(site.name());
  if (!plan.sites.subnet().empty()) spec.subnet = plan.sites.subnet();
  remove_stale_namespaces();
  // Declared before the processes so that it is destroyed after them: processes stop first, then
  // their namespaces go.
  NamespaceTopology topology(spec);
  result.namespaces = topology.namespaces();

  std::vector<std::string> peers;
  for (const auto& site : topology.sites()) peers.push_back(site.address);
  std::map<std::string, std::string> dds_uri;
  for (const auto& site : topology.sites()) {
    dds_uri[site.name] =
        write_dds_config({site.interface, peers, 32}, result.output_dir / ("dds_" + site.name + ".xml"));
  }

  const std::string run_id = make_run_id();
  const int domain = plan.study.deployment().domain_id();
  std::vector<std::unique_ptr<ChildProcess>> nodes;
  std::unique_ptr<ChildProcess> coordinator;
  for (const auto& placement : plan.placements) {
    auto argv = topology.exec_prefix(placement.site);
    const std::map<std::string, std::string> env{{"CYCLONEDDS_URI", dds_uri.at(placement.site)}};
    const auto log = result.output_dir / (placement.node_id == 0
                                              ? std::string("coordinator.log")
                                              : "node_" + std::to_string(placement.node_id) + ".log");
    if (placement.node_id == 0) continue;  // started last, once every node listens
    argv.push_back(placement.kind == "substructure" ? programs.substructure.string()
                                                    : programs.actuator_emulator.string());
    for (const auto& arg : {std::string("--node-id"), std::to_string(placement.node_id),
                            std::string("--domain"), std::to_string(domain),
                            std::string("--run-id"), run_id}) {
      argv.push_back(arg);
    }
    const auto security_args = security::security_arguments(security_dir, placement.node_id);
    argv.insert(argv.end(), security_args.begin(), security_args.end());
    spdlog::info("site {}: {}", placement.site, command_line(argv));
    nodes.push_back(std::make_unique<ChildProcess>(
        "node " + std::to_string(placement.node_id) + " (" + placement.kind + ") at site " +
            placement.site,
        argv, env, log));
  }
  {
    const auto& site = plan.placements.front().site;  // node 0, placed first by plan_sites
    auto argv = topology.exec_prefix(site);
    for (const auto& arg : {programs.coordinator.string(), std::string("--config"),
                            study_path.string(), std::string("--record"), result.record.string(),
                            std::string("--run-id"), run_id, std::string("--domain"),
                            std::to_string(domain)}) {
      argv.push_back(arg);
    }
    const auto security_args = security::security_arguments(security_dir, 0);
    argv.insert(argv.end(), security_args.begin(), security_args.end());
    spdlog::info("site {}: {}", site, command_line(argv));
    coordinator = std::make_unique<ChildProcess>("coordinator at site " + site, argv,
                                                 std::map<std::string, std::string>{
                                                     {"CYCLONEDDS_URI", dds_uri.at(site)}},
                                                 result.output_dir / "coordinator.log");
  }

  const auto deadline = started + std::chrono::duration<double>(plan.timeout);
  std::optional<int> exit_code;
  while (!(exit_code = coordinator->wait_for(std::chrono::milliseconds(20)))) {
    if (options.stop_requested && options.stop_requested()) {
      result.status = "interrupted";
      break;
    }
    if (std::chrono::steady_clock::now() > deadline) {
      result.status = "timed out after " + std::to_string(plan.timeout) + " s";
      break;
    }
  }
  if (!exit_code) exit_code = coordinator->terminate();
  result.coordinator_exit = *exit_code;
  // After an orderly end the nodes got STOP and exit by themselves; otherwise do not wait long.
  const auto grace = result.status.empty() ? kNodeExitGrace : std::chrono::seconds(1);
  for (auto& node : nodes) {
    if (!node->wait_for(grace)) {
      spdlog::warn("{} did not exit after the coordinator; stopping it", node->name());
    }
    node->terminate();
  }
  result.wall_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();

  if (std::filesystem::exists(result.record)) {
    const auto contents = runtime::read_record(result.record);
    result.steps = static_cast<std::int64_t>(contents.steps().size());
    if (const auto* footer = contents.footer()) {
      if (result.status.empty()) result.status = footer->status();
      result.failed_node = footer->failed_node();
      result.record_wall_seconds = footer->wall_seconds();
      result.ok = footer->ok() && result.coordinator_exit == 0;
    } else if (result.status.empty()) {
      result.status = "the record has no footer (the coordinator stopped abruptly)";
    }
    result.links = measure_links(result.record, plan);
  } else if (result.status.empty()) {
    result.status = "no record written; coordinator log: " + coordinator->log_tail(1500);
  }
  if (!result.ok && result.status.empty()) {
    result.status = "coordinator exit " + std::to_string(result.coordinator_exit);
  }
  return result;  // processes, then namespaces, are removed here
}

std::string check_record(const std::filesystem::path& record, std::int64_t min_steps,
                         double expected_injected) {
  const auto contents = runtime::read_record(record);
  const auto* footer = contents.footer();
  if (footer == nullptr) throw std::runtime_error(record.string() + ": no footer (run cut short)");
  if (!footer->ok()) throw std::runtime_error(record.string() + ": run failed: " + footer->status());
  const auto steps = static_cast<std::int64_t>(contents.steps().size());
  if (steps < min_steps) {
    throw std::runtime_error(record.string() + ": " + std::to_string(steps) + " steps, expected >= " +
                             std::to_string(min_steps));
  }
  const runtime::RunMeasurements measured = runtime::measure_run(contents);
  std::ostringstream text;
  text << record.string() << ": " << steps << " steps, status " << footer->status() << "\n";
  double largest_injected = 0.0;
  for (const auto& [node, series] : measured.links) {
    const auto in = series.injected_summary();
    const auto rt = series.round_trip_summary();
    largest_injected = std::max(largest_injected, in.median);
    text << "  node " << node << ": injected median " << in.median * 1e3 << " ms, round trip median "
         << rt.median * 1e3 << " ms (p99 " << rt.p99 * 1e3 << " ms)\n";
    if (rt.median + 1e-4 < in.median) {
      throw std::runtime_error(text.str() + "node " + std::to_string(node) +
                               ": measured round trip is below the injected lag");
    }
  }
  if (expected_injected >= 0.0 && std::abs(largest_injected - expected_injected) > 1e-4) {
    throw std::runtime_error(text.str() + "largest injected lag " + std::to_string(largest_injected) +
                             " s, expected " + std::to_string(expected_injected) + " s");
  }
  return text.str();
}

namespace {
nlohmann::json summary_json(const runtime::LagSummary& s) {
  return {{"count", s.count}, {"mean_s", s.mean}, {"median_s", s.median}, {"p99_s", s.p99},
          {"max_s", s.max}};
}
}  // namespace

nlohmann::json to_json(const SitesRunResult& result) {
  nlohmann::json links = nlohmann::json::array();
  for (const auto& link : result.links) {
    links.push_back({{"node_id", link.node_id},
                     {"kind", link.kind},
                     {"site", link.site},
                     {"configured_to_node_s", link.configured_to_node},
                     {"configured_from_node_s", link.configured_from_node},
                     {"injected", summary_json(link.injected)},
                     {"round_trip", summary_json(link.round_trip)},
                     {"one_way_down", summary_json(link.one_way_down)},
                     {"one_way_up", summary_json(link.one_way_up)}});
  }
  return {{"ok", result.ok},
          {"status", result.status},
          {"failed_node", result.failed_node},
          {"coordinator_exit", result.coordinator_exit},
          {"steps", result.steps},
          {"wall_seconds", result.wall_seconds},
          {"record_wall_seconds", result.record_wall_seconds},
          {"record", result.record.string()},
          {"output_dir", result.output_dir.string()},
          {"namespaces", result.namespaces},
          {"links", links}};
}

std::string to_text(const SitesRunResult& result) {
  std::ostringstream out;
  auto ms = [](double s) { return s * 1e3; };
  out << "status: " << result.status << (result.ok ? "" : " (FAILED)") << "\n";
  if (!result.failed_node.empty()) out << "failed node: " << result.failed_node << "\n";
  out << "steps: " << result.steps << ", wall " << result.wall_seconds << " s\n";
  out << "record: " << result.record.string() << "\n";
  out.setf(std::ios::fixed);
  out.precision(2);
  for (const auto& link : result.links) {
    out << "link coordinator <-> node " << link.node_id << " (" << link.kind << ", site "
        << link.site << "): injected " << ms(link.configured_to_node) << " + "
        << ms(link.configured_from_node) << " ms configured, " << ms(link.injected.median)
        << " ms reported; round trip median " << ms(link.round_trip.median) << " ms (p99 "
        << ms(link.round_trip.p99) << ", max " << ms(link.round_trip.max)
        << "), one-way down/up median " << ms(link.one_way_down.median) << "/"
        << ms(link.one_way_up.median) << " ms\n";
  }
  out << "namespaces made and removed: " << result.namespaces.size() << "\n";
  return out.str();
}

}  // namespace rths::deploy
