#include "deploy/netns.h"

#include <signal.h>
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <regex>
#include <sstream>

#include "util/process.h"

namespace rths::deploy {

using util::CommandResult;
using util::run_checked;
using util::run_command;
using util::tool_available;
namespace {

constexpr const char* kPrefix = "rths-";
constexpr const char* kBridge = "br0";
constexpr const char* kSiteInterface = "eth0";

}  // namespace

void validate_topology(const TopologySpec& spec) {
  if (spec.sites.empty()) throw std::invalid_argument("topology: no sites");
  if (spec.sites.size() > 200) throw std::invalid_argument("topology: more than 200 sites");
  const std::regex name_rule("[a-z0-9_]{1,16}");
  for (std::size_t i = 0; i < spec.sites.size(); ++i) {
    const auto& name = spec.sites[i];
    if (!std::regex_match(name, name_rule)) {
      throw std::invalid_argument("topology: site name '" + name +
                                  "' must be 1..16 characters of [a-z0-9_]");
    }
    if (name == "hub") throw std::invalid_argument("topology: site name 'hub' is reserved");
    if (std::count(spec.sites.begin(), spec.sites.end(), name) > 1) {
      throw std::invalid_argument("topology: site '" + name + "' appears twice");
    }
  }
  const std::regex subnet_rule(R"((\d{1,3})\.(\d{1,3})\.(\d{1,3}))");
  std::smatch m;
  if (!std::regex_match(spec.subnet, m, subnet_rule) || std::stoi(m[1]) > 255 ||
      std::stoi(m[2]) > 255 || std::stoi(m[3]) > 255) {
    throw std::invalid_argument("topology: subnet '" + spec.subnet +
                                "' must be three octets, e.g. 10.231.0");
  }
  // The bridge owns the /24: a loopback (127/8), "this network" (0/8) or multicast and reserved
  // (224 and up) prefix is no subnet a site can be given.
  const int first = std::stoi(m[1]);
  if (first == 0 || first == 127 || first >= 224)
    throw std::invalid_argument("topology: subnet '" + spec.subnet +
                                "' is not a unicast network for the sites (0, 127 and 224-255 are "
                                "this network, loopback, multicast and reserved), e.g. 10.231.0");
}

namespace {

// Unique per process and per instance without a mutable global: pid + a clock nonce.
std::string unique_prefix() {
  const auto nonce =
      static_cast<unsigned long long>(std::chrono::steady_clock::now().time_since_epoch().count());
  std::ostringstream out;
  out << kPrefix << ::getpid() << '-' << std::hex << ((nonce >> 10) & 0xffffff) << '-';
  return out.str();
}

std::string trimmed(std::string text) {
  while (!text.empty() && (text.back() == '\n' || text.back() == ' ')) text.pop_back();
  return text;
}

bool looks_like_permission_problem(const std::string& output) {
  return output.find("Operation not permitted") != std::string::npos ||
         output.find("Permission denied") != std::string::npos;
}

}  // namespace

std::vector<std::string> parse_namespace_list(const std::string& output) {
  std::vector<std::string> names;
  std::istringstream lines(output);
  std::string line;
  static const std::regex name_line(R"(([A-Za-z0-9_.-]+)( \(id: [0-9]+\))?)");
  while (std::getline(lines, line)) {
    std::smatch m;
    if (std::regex_match(line, m, name_line)) names.push_back(m[1].str());
  }
  return names;
}

std::vector<std::string> list_namespaces() {
  return parse_namespace_list(util::run_checked({"ip", "netns", "list"}));
}

std::optional<std::string> namespace_support() {
  if (!util::tool_available("ip"))
    return "the `ip` tool (Debian package iproute2) is not installed";
  const std::string probe = unique_prefix() + "probe";
  util::CommandResult added;
  try {
    added = util::run_command({"ip", "netns", "add", probe});
  } catch (const std::exception& e) {
    return std::string("cannot run `ip`: ") + e.what();
  }
  if (!added.ok()) {
    std::string reason = "network namespaces are not permitted here (`ip netns add` failed: " +
                         trimmed(added.output) + ")";
    if (looks_like_permission_problem(added.output)) {
      reason += "; run as root or with CAP_SYS_ADMIN and CAP_NET_ADMIN";
    }
    return reason;
  }
  util::run_command({"ip", "netns", "del", probe});
  return std::nullopt;
}

std::vector<std::string> remove_stale_namespaces() {
  std::vector<std::string> removed;
  const std::regex owned(R"(rths-(\d+)-[0-9a-f]+-[a-z0-9_]+)");
  for (const auto& name : list_namespaces()) {
    std::smatch m;
    if (!std::regex_match(name, m, owned)) continue;
    const long pid = std::stol(m[1]);
    const bool alive = ::kill(static_cast<pid_t>(pid), 0) == 0 || errno == EPERM;
    if (alive) continue;
    if (util::run_command({"ip", "netns", "del", name}).ok()) removed.push_back(name);
  }
  return removed;
}

NamespaceTopology::NamespaceTopology(const TopologySpec& spec) {
  validate_topology(spec);
  if (!util::tool_available("ip")) {
    throw NamespacesUnavailable("the `ip` tool (Debian package iproute2) is not installed");
  }
  prefix_ = unique_prefix();
  hub_ = prefix_ + "hub";
  try {
    build(spec);
  } catch (...) {
    teardown();
    throw;
  }
}

NamespaceTopology::~NamespaceTopology() { teardown(); }

void NamespaceTopology::build(const TopologySpec& spec) {
  auto add_namespace = [this](const std::string& name) {
    const auto result = util::run_command({"ip", "netns", "add", name});
    if (!result.ok()) {
      const std::string why =
          "cannot create network namespace " + name + ": " + trimmed(result.output);
      if (looks_like_permission_problem(result.output)) {
        throw NamespacesUnavailable(why + " (run as root or with CAP_SYS_ADMIN and CAP_NET_ADMIN)");
      }
      throw std::runtime_error(why);
    }
    created_.push_back(name);
    util::run_checked({"ip", "-n", name, "link", "set", "lo", "up"});
  };
  add_namespace(hub_);
  util::run_checked({"ip", "-n", hub_, "link", "add", kBridge, "type", "bridge"});
  util::run_checked({"ip", "-n", hub_, "link", "set", kBridge, "up"});
  for (std::size_t i = 0; i < spec.sites.size(); ++i) {
    Site site;
    site.name = spec.sites[i];
    site.netns = prefix_ + site.name;
    site.interface = kSiteInterface;
    site.address = spec.subnet + "." + std::to_string(i + 1);
    add_namespace(site.netns);
    // The veth pair is made inside the hub, so its names never meet the host's interfaces.
    const std::string port = "p" + std::to_string(i + 1);
    util::run_checked({"ip", "-n", hub_, "link", "add", port, "type", "veth", "peer", "name",
                       site.interface, "netns", site.netns});
    util::run_checked({"ip", "-n", hub_, "link", "set", port, "master", kBridge});
    util::run_checked({"ip", "-n", hub_, "link", "set", port, "up"});
    util::run_checked(
        {"ip", "-n", site.netns, "addr", "add", site.address + "/24", "dev", site.interface});
    util::run_checked({"ip", "-n", site.netns, "link", "set", site.interface, "up"});
    sites_.push_back(site);
  }
}

const Site& NamespaceTopology::site(const std::string& name) const {
  for (const auto& s : sites_) {
    if (s.name == name) return s;
  }
  throw std::invalid_argument("topology: no site named '" + name + "'");
}

std::vector<std::string> NamespaceTopology::exec_prefix(const std::string& site_name) const {
  return {"ip", "netns", "exec", site(site_name).netns};
}

std::vector<std::string> NamespaceTopology::namespaces() const {
  std::vector<std::string> names;
  for (const auto& s : sites_) names.push_back(s.netns);
  if (!created_.empty()) names.push_back(hub_);
  return names;
}

void NamespaceTopology::teardown() {
  // Sites first, hub last: deleting a site namespace destroys its veth end and so the hub port.
  for (auto it = created_.rbegin(); it != created_.rend(); ++it) {
    try {
      const auto result = util::run_command({"ip", "netns", "del", *it});
      if (!result.ok()) spdlog::warn("cannot delete namespace {}: {}", *it, result.output);
    } catch (const std::exception& e) {
      spdlog::warn("cannot delete namespace {}: {}", *it, e.what());
    }
  }
  created_.clear();
  sites_.clear();
}

}  // namespace rths::deploy
