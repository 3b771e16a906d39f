#include "deploy/sites.h"

#include <fmt/format.h>
#include <google/protobuf/io/tokenizer.h>
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <fstream>
#include <map>
#include <memory>
#include <set>
#include <sstream>
#include <thread>

#include "deploy/dds_config.h"
#include "deploy/netns.h"
#include "runtime/record/measurements.h"
#include "runtime/record/record.h"
#include "study/study.h"
#include "study/text_format.h"
#include "util/process.h"

namespace rths::deploy {
namespace {

constexpr double kDefaultTimeout = 300.0;  // s
constexpr const char* kDefaultSubnet = "10.231.0";

std::string kind_name(config::NodeSpec::Kind kind) {
  switch (kind) {
    case config::NodeSpec::SUBSTRUCTURE: return "substructure";
    case config::NodeSpec::ACTUATOR_EMULATOR: return "actuator_emulator";
    case config::NodeSpec::CONTROLLER: return "controller";
    default: return "unspecified";
  }
}

void make_absolute(std::string& path, const std::filesystem::path& base_dir) {
  if (!path.empty() && std::filesystem::path(path).is_relative()) {
    path = std::filesystem::absolute(base_dir / path).lexically_normal().string();
  }
}

// The merged study is written elsewhere than the original, so its relative paths must not move.
void absolutize_paths(config::Study& study, const std::filesystem::path& base_dir) {
  make_absolute(*study.mutable_motion()->mutable_path(), base_dir);
  if (study.has_deployment())
    make_absolute(*study.mutable_deployment()->mutable_security_dir(), base_dir);
  for (auto& motion : *study.mutable_sweep()->mutable_motions()) {
    make_absolute(*motion.mutable_path(), base_dir);
  }
  for (auto& study_case : *study.mutable_cases()) {
    for (auto& stage : *study_case.mutable_delay()) {
      if (stage.has_trace()) make_absolute(*stage.mutable_trace()->mutable_path(), base_dir);
    }
  }
}

// A time in s that is finite and >= 0 (0: the default); NaN fails every comparison, so it is
// refused by name, never read as 0.
void check_seconds(double value, const char* field, const std::string& source) {
  if (!(std::isfinite(value) && value >= 0.0))
    throw std::invalid_argument(fmt::format(
        "{}: {} {} s is not a time (finite, >= 0; 0 = the default)", source, field, value));
}

// Merges this file's deployment and its overrides (domain, case, clock, duration, timeout) into
// the study.
void apply_overrides(const Sites& sites, SitesPlan& plan, const std::string& source) {
  if (sites.has_deployment()) {
    if (plan.study.has_deployment()) {
      throw std::invalid_argument(source + ": deployment is given here and in " +
                                  plan.study_file.string() + "; keep one");
    }
    *plan.study.mutable_deployment() = sites.deployment();
  }
  if (!plan.study.has_deployment() || plan.study.deployment().nodes().empty()) {
    throw std::invalid_argument(source + ": no nodes: neither " + plan.study_file.string() +
                                " nor this file has deployment.nodes");
  }
  auto& deployment = *plan.study.mutable_deployment();
  if (sites.domain_id() < 0 || sites.domain_id() > 232) {
    throw std::invalid_argument(source + ": domain_id must be in 0..232");
  }
  if (sites.domain_id() != 0) deployment.set_domain_id(sites.domain_id());
  if (!sites.case_name().empty()) deployment.set_case_name(sites.case_name());
  if (!Sites::Clock_IsValid(sites.clock()))  // proto3 keeps an unknown number (clock: -1)
    throw std::invalid_argument(
        fmt::format("{}: clock {} is not STUDY (0), LOCKSTEP (1) or REAL_TIME (2)", source,
                    static_cast<int>(sites.clock())));
  if (sites.clock() == Sites::LOCKSTEP) deployment.set_clock(config::Deployment::LOCKSTEP);
  if (sites.clock() == Sites::REAL_TIME) deployment.set_clock(config::Deployment::REAL_TIME);
  check_seconds(sites.duration(), "duration", source);
  if (sites.duration() > 0.0) plan.study.mutable_motion()->set_duration(sites.duration());
  check_seconds(sites.timeout(), "timeout", source);
  plan.timeout = sites.timeout() > 0.0 ? sites.timeout() : kDefaultTimeout;
}

// Every declared node and the coordinator sits at exactly one site.
void place_nodes(const Sites& sites, const std::map<int, config::NodeSpec*>& nodes, SitesPlan& plan,
                 const std::string& source) {
  if (sites.sites().empty()) throw std::invalid_argument(source + ": no sites");
  std::map<int, std::string> site_of;
  for (const auto& site : sites.sites()) {
    for (const int id : site.node_ids()) {
      const std::string where = source + ": site '" + site.name() + "'";
      if (id != 0 && nodes.count(id) == 0) {
        throw std::invalid_argument(where + " places node " + std::to_string(id) +
                                    ", which the study's deployment does not declare");
      }
      if (site_of.count(id) != 0) {
        throw std::invalid_argument(where + " places node " + std::to_string(id) +
                                    ", already placed at site '" + site_of[id] + "'");
      }
      site_of[id] = site.name();
    }
  }
  if (site_of.count(0) == 0) {
    throw std::invalid_argument(source + ": the coordinator (node 0) is not placed at any site");
  }
  plan.placements.push_back({0, "coordinator", site_of[0]});
  for (const auto& [id, node] : nodes) {
    if (site_of.count(id) == 0) {
      throw std::invalid_argument(source + ": node " + std::to_string(id) + " (" +
                                  kind_name(node->kind()) + ") is not placed at any site");
    }
    plan.placements.push_back({id, kind_name(node->kind()), site_of[id]});
  }
}

// Each link sets one node's lags, checked by the study's own lag rule.
void apply_links(const Sites& sites, const std::map<int, config::NodeSpec*>& nodes,
                 const SitesPlan& plan, const std::string& source) {
  std::set<int> linked;
  for (const auto& link : sites.links()) {
    const std::string where = source + ": link to node " + std::to_string(link.node_id());
    if (nodes.count(link.node_id()) == 0) {
      throw std::invalid_argument(where + ": no such node in the study's deployment");
    }
    if (!linked.insert(link.node_id()).second) throw std::invalid_argument(where + " given twice");
    // The one lag rule, with the study's allow_long_lag, as for the study's own deployment.
    study::validate_link_lag(link.to_node(), where + " to_node", plan.study.allow_long_lag(),
                             source);
    study::validate_link_lag(link.from_node(), where + " from_node", plan.study.allow_long_lag(),
                             source);
    *nodes.at(link.node_id())->mutable_receive_lag() = link.to_node();
    *nodes.at(link.node_id())->mutable_send_lag() = link.from_node();
  }
}

// Under LOCKSTEP a lost message stops the run, so no lag may lose messages.
void check_lockstep_loss(const config::Deployment& deployment, const std::string& source) {
  if (deployment.clock() == config::Deployment::LOCKSTEP) {
    for (const auto& node : deployment.nodes()) {
      if (node.receive_lag().loss() > 0.0 || node.send_lag().loss() > 0.0) {
        throw std::invalid_argument(source + ": node " + std::to_string(node.id()) +
                                    " has a lag with loss > 0, but the clock is LOCKSTEP, where a "
                                    "lost message stops the run; use clock: REAL_TIME or loss: 0");
      }
    }
  }
}

void check_topology(const Sites& sites, const std::string& source) {
  TopologySpec topology;
  for (const auto& site : sites.sites()) topology.sites.push_back(site.name());
  topology.subnet = sites.subnet().empty() ? kDefaultSubnet : sites.subnet();
  try {
    validate_topology(topology);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(source + ": " + e.what());
  }
}

}  // namespace

Sites parse_sites(const std::string& text, const std::string& source_name) {
  Sites sites;
  study::parse_text_format(text, source_name, sites);
  return sites;
}

SitesPlan load_sites(const std::filesystem::path& sites_file) {
  const auto sites =
      parse_sites(study::read_text_file(sites_file, "sites config"), sites_file.string());
  auto plan = plan_sites(sites, sites_file.parent_path(), sites_file.string());
  plan.sites_file = sites_file;
  return plan;
}

SitesPlan plan_sites(const Sites& sites, const std::filesystem::path& base_dir,
                     const std::string& source) {
  SitesPlan plan;
  plan.sites = sites;
  if (sites.study().empty()) throw std::invalid_argument(source + ": study is empty");
  plan.study_file = base_dir / sites.study();
  plan.study = study::load_study(plan.study_file);
  apply_overrides(sites, plan, source);
  auto& deployment = *plan.study.mutable_deployment();

  std::map<int, config::NodeSpec*> nodes;
  for (auto& node : *deployment.mutable_nodes()) nodes[node.id()] = &node;
  place_nodes(sites, nodes, plan, source);
  apply_links(sites, nodes, plan, source);
  check_lockstep_loss(deployment, source);
  absolutize_paths(plan.study, std::filesystem::absolute(plan.study_file).parent_path());
  // The topology checks names and the subnet; check now so the error names this file.
  check_topology(sites, source);
  return plan;
}

std::vector<LinkMeasurement> measure_links(const std::filesystem::path& record,
                                           const SitesPlan& plan) {
  const runtime::RunMeasurements measured = runtime::measure_run(runtime::read_record(record));
  std::vector<LinkMeasurement> links;
  for (const auto& placement : plan.placements) {
    if (placement.node_id == 0) continue;
    LinkMeasurement link;
    link.node_id = placement.node_id;
    link.kind = placement.kind;
    link.site = placement.site;
    for (const auto& node : plan.study.deployment().nodes()) {
      if (node.id() != placement.node_id) continue;
      link.configured_to_node = node.receive_lag().one_way_delay();
      link.configured_from_node = node.send_lag().one_way_delay();
    }
    const auto series = measured.links.find(link.node_id);
    if (series != measured.links.end()) {
      link.injected = series->second.injected_summary();
      link.round_trip = series->second.round_trip_summary();
      link.one_way_down = runtime::summarize(series->second.one_way_down);
      link.one_way_up = runtime::summarize(series->second.one_way_up);
    }
    links.push_back(link);
  }
  return links;
}

}  // namespace rths::deploy
