#pragma once
// A topology of Linux network namespaces on this host: one namespace per site, all joined to a
// bridge in a private hub namespace through veth pairs, on one IPv4 subnet.
//
//      site "coordinator" (ns rths-<pid>-<tag>-coordinator)  eth0 10.231.0.1/24 ─┐
//      site "lab_a"       (ns rths-<pid>-<tag>-lab_a)        eth0 10.231.0.2/24 ─┼─ br0 (ns ...-hub)
//      site "lab_b"       (ns rths-<pid>-<tag>-lab_b)        eth0 10.231.0.3/24 ─┘
//
// Every topology has its own hub, so concurrent topologies (tests side by side) share no link and
// may reuse the same addresses. The host's own namespaces and routes are never touched.
// Lag is not put on the links (kernel netem is unavailable here): the nodes inject it themselves.
//
// Lifetime: the constructor builds everything or, on any failure, removes what it made and
// throws. The destructor (or teardown()) deletes every namespace it created, which also removes
// the veth pairs and the bridge. Namespaces left by a killed process are found by the pid in
// their name and removed by remove_stale_namespaces().
//
// Needs: iproute2 (`ip`), root or CAP_SYS_ADMIN + CAP_NET_ADMIN. When namespaces cannot be made,
// NamespacesUnavailable says why.

#include <filesystem>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace rths::deploy {

// The environment cannot create network namespaces (no permission, no `ip`, no kernel support).
struct NamespacesUnavailable : std::runtime_error {
  using std::runtime_error::runtime_error;
};

struct TopologySpec {
  std::vector<std::string> sites;   // names: [a-z0-9_], 1..16 characters, unique
  std::string subnet = "10.231.0";  // first three octets of the /24; sites get .1, .2, ...
};

struct Site {
  std::string name;
  std::string netns;      // namespace name (for `ip netns exec`)
  std::string interface;  // the site's veth end inside its namespace: "eth0"
  std::string address;    // IPv4 without prefix length
};

class NamespaceTopology {
 public:
  explicit NamespaceTopology(const TopologySpec& spec);
  ~NamespaceTopology();
  NamespaceTopology(const NamespaceTopology&) = delete;
  NamespaceTopology& operator=(const NamespaceTopology&) = delete;

  const std::vector<Site>& sites() const { return sites_; }
  // Throws std::invalid_argument naming the site when it is not in the topology.
  const Site& site(const std::string& name) const;
  // argv prefix that runs a program inside the site's namespace.
  std::vector<std::string> exec_prefix(const std::string& site_name) const;
  // Deletes every namespace made; safe to call twice. Errors are logged, not thrown.
  void teardown();
  // Namespaces this topology currently owns (hub last).
  std::vector<std::string> namespaces() const;

 private:
  void build(const TopologySpec& spec);
  std::string prefix_;
  std::string hub_;
  std::vector<Site> sites_;
  std::vector<std::string> created_;  // in creation order
};

// Throws std::invalid_argument naming the bad site name, duplicate or subnet (three octets of a
// unicast network: not 0, 127 (loopback) or 224-255 (multicast, reserved)).
void validate_topology(const TopologySpec& spec);

// nullopt when this process can create and delete a network namespace, else the reason.
std::optional<std::string> namespace_support();

// Removes namespaces named rths-<pid>-... whose pid is no longer running. Returns their names.
std::vector<std::string> remove_stale_namespaces();

// Names of all namespaces currently on the host (`ip netns list`).
std::vector<std::string> list_namespaces();
// The names in `ip netns list`'s output: a line "name" or "name (id: N)" per namespace; any other
// line (its stderr, interleaved: "Error: Peer netns reference is invalid." for a namespace being
// deleted meanwhile) names none.
std::vector<std::string> parse_namespace_list(const std::string& output);

}  // namespace rths::deploy
