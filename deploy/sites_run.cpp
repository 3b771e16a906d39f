// run_sites: topology and DDS configs around the one launch sequence (runtime/launch/launch.h),
// then the record summary; everything undone on exit.
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
#include "deploy/sites.h"
#include "runtime/launch/launch.h"
#include "runtime/record/measurements.h"
#include "runtime/record/record.h"
#include "security/check.h"
#include "study/study.h"

namespace rths::deploy {
namespace {

// The study as run, beside the record, with where it came from.
void write_study_copy(const SitesPlan& plan, const std::filesystem::path& path) {
  std::string text;
  google::protobuf::TextFormat::PrintToString(plan.study, &text);
  std::ofstream out(path);
  out << "# Written by `rths sites` from " << plan.study_file.string() << " and "
      << plan.sites_file.string() << "\n"
      << text;
  if (!out) throw std::runtime_error("cannot write " + path.string());
}

// One Cyclone DDS config per site: its own interface, every site's address as a peer.
std::map<std::string, std::string> site_dds_configs(const NamespaceTopology& topology,
                                                    const std::filesystem::path& dir) {
  std::vector<std::string> peers;
  for (const auto& site : topology.sites()) peers.push_back(site.address);
  std::map<std::string, std::string> dds_uri;
  for (const auto& site : topology.sites())
    dds_uri[site.name] =
        write_dds_config({site.interface, peers, 32}, dir / ("dds_" + site.name + ".xml"));
  return dds_uri;
}

// The outcome as the record tells it (footer, steps, measured links), else as the launch did.
void read_outcome(const SitesPlan& plan, const runtime::LaunchResult& launched,
                  SitesRunResult& result) {
  result.run_id = launched.run_id;
  result.case_name = launched.case_name;
  result.status = launched.status;
  result.coordinator_exit = launched.coordinator_exit;
  result.wall_seconds = launched.wall_seconds;
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
    result.status = "no record written; coordinator log: " + launched.coordinator_log_tail;
  }
  if (!result.ok && result.status.empty())
    result.status = "coordinator exit " + std::to_string(result.coordinator_exit);
}

}  // namespace

SitesRunResult run_sites(const SitesPlan& plan, const SitesRunOptions& options) {
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
  // Named as `rths launch` names its records: the case that runs (launch_run finds it the same way).
  result.record =
      result.output_dir /
      (study::find_case(plan.study, plan.study.deployment().case_name()).name() + ".rthsrec");
  std::filesystem::remove(result.record);
  const auto study_path = result.output_dir / "study.textproto";
  write_study_copy(plan, study_path);

  TopologySpec spec;
  for (const auto& site : plan.sites.sites()) spec.sites.push_back(site.name());
  if (!plan.sites.subnet().empty()) spec.subnet = plan.sites.subnet();
  remove_stale_namespaces();
  // Lives past launch_run, which stops every process: processes stop first, then their
  // namespaces go.
  NamespaceTopology topology(spec);
  result.namespaces = topology.namespaces();
  const std::map<std::string, std::string> dds_uri = site_dds_configs(topology, result.output_dir);
  std::map<int, std::string> site_of;
  for (const auto& placement : plan.placements) site_of[placement.node_id] = placement.site;

  runtime::LaunchOptions launch;
  launch.config = study_path;
  launch.record = result.record;
  launch.log_dir = result.output_dir;
  launch.timeout = plan.timeout;
  if (options.bin_dir) launch.programs_dir = *options.bin_dir;
  launch.security_dir = security_dir;
  // The measured network lag is the point of a sites run: leave the processes to the scheduler.
  launch.cpu_placement = runtime::CpuPlacement::kSpread;
  launch.stop_requested = options.stop_requested;
  launch.platform_file = options.platform_file;
  launch.accept_platform = options.accept_platform;
  launch.platform_seconds = options.platform_seconds;
  launch.coordinator_args = options.coordinator_args;
  launch.placement = [&](int node_id) {
    const std::string& site = site_of.at(node_id);
    return runtime::Placement{
        topology.exec_prefix(site), {{"CYCLONEDDS_URI", dds_uri.at(site)}}, "site " + site};
  };
  read_outcome(plan, runtime::launch_run(launch), result);
  return result;  // the namespaces are removed here
}

std::string check_record(const std::filesystem::path& record, std::int64_t min_steps,
                         double expected_injected) {
  const auto contents = runtime::read_record(record);
  const auto* footer = contents.footer();
  if (footer == nullptr) throw std::runtime_error(record.string() + ": no footer (run cut short)");
  if (!footer->ok())
    throw std::runtime_error(record.string() + ": run failed: " + footer->status());
  const auto steps = static_cast<std::int64_t>(contents.steps().size());
  if (steps < min_steps) {
    throw std::runtime_error(record.string() + ": " + std::to_string(steps) +
                             " steps, expected >= " + std::to_string(min_steps));
  }
  const runtime::RunMeasurements measured = runtime::measure_run(contents);
  std::ostringstream text;
  text << record.string() << ": " << steps << " steps, status " << footer->status() << "\n";
  double largest_injected = 0.0;
  for (const auto& [node, series] : measured.links) {
    const auto in = series.injected_summary();
    const auto rt = series.round_trip_summary();
    largest_injected = std::max(largest_injected, in.median);
    text << "  node " << node << ": injected median " << in.median * 1e3
         << " ms, round trip median " << rt.median * 1e3 << " ms (p99 " << rt.p99 * 1e3 << " ms)\n";
    if (rt.median + 1e-4 < in.median) {
      throw std::runtime_error(text.str() + "node " + std::to_string(node) +
                               ": measured round trip is below the injected lag");
    }
  }
  if (expected_injected >= 0.0 && std::abs(largest_injected - expected_injected) > 1e-4) {
    throw std::runtime_error(text.str() + "largest injected lag " +
                             std::to_string(largest_injected) + " s, expected " +
                             std::to_string(expected_injected) + " s");
  }
  return text.str();
}

namespace {
nlohmann::json summary_json(const runtime::LagSummary& s) {
  return {{"count", s.count},
          {"mean_s", s.mean},
          {"median_s", s.median},
          {"p99_s", s.p99},
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
