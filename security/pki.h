#pragma once
// A lab's DDS Security PKI (`rths pki init DIR`): one lab CA, one identity per node, and the
// governance and permissions documents Cyclone DDS's built-in plugins (auth, access control,
// crypto) read, signed by the CA as S/MIME (PKCS#7, detached, text).
//
// Layout written under DIR (every node directory is self-contained: it is what a lab hands to
// the site that runs that node; the CA key never leaves DIR/ca):
//   ca/ca_cert.pem ca/ca_key.pem (0600)                lab CA, EC P-256, self-signed
//   governance.xml                                      readable copy of the signed governance
//   node_<id>/identity_ca.pem                           the CA certificate (identity + permissions CA)
//   node_<id>/cert.pem node_<id>/key.pem (0600)         the node's identity, subject
//                                                       "CN=rths-node-<id>,OU=<kind>,O=<organisation>"
//   node_<id>/governance.p7s                            the domain's governance, signed
//   node_<id>/permissions.xml node_<id>/permissions.p7s one grant: the node's subject, its topics
//
// Governance: domains 0-230 (the most Cyclone's access control parser accepts), no
// unauthenticated participants, join access control on, discovery, liveliness, RTPS messages
// and every topic's metadata and data encrypted (AES-GCM), read and write access control on
// every topic.
// Permissions (default DENY): the coordinator (node 0) publishes "*_down" (commands) and
// subscribes "*_up"; node N (a substructure node or an actuator emulator) publishes
// "*_node<N>_up" and subscribes "*_node<N>_down", its own two topics and nothing else
// (transport/dds_endpoint.h: topics <prefix>_node<id>_down and <prefix>_node<id>_up). So a
// certificate of node 2 cannot publish as node 1: DDS refuses the writer.
// Validity: certificates and grants from one hour before creation (clock skew between sites)
// to `days` after it.

#include <chrono>
#include <filesystem>
#include <string>
#include <vector>

namespace rths::security {

inline constexpr int kCoordinatorNodeId = 0;

struct NodeIdentity {
  int node_id = 0;   // 0 = coordinator
  std::string kind;  // "coordinator", "substructure", "actuator_emulator" or "controller"
};

struct PkiOptions {
  std::string organisation = "rths-lab";  // O= of every subject; letters, digits, '-', '_', '.'
  int days = 365;                         // validity of certificates and grants (>= 1)
  std::vector<NodeIdentity> nodes;        // the coordinator is added when missing
};

// Validity window relative to now (s; negative = in the past).
struct Validity {
  std::chrono::seconds not_before{-3600};
  std::chrono::seconds not_after{365 * 86400};
};

// "CN=rths-node-<id>,OU=<kind>,O=<organisation>".
std::string subject_name(const NodeIdentity& node, const std::string& organisation);

// Throws std::invalid_argument for an unknown kind, a negative id, or node 0 not being the
// coordinator (and vice versa).
void check_identity(const NodeIdentity& node);

// Writes the whole layout. Refuses (std::invalid_argument) bad options and a DIR that already
// holds a CA (a second init would orphan every certificate handed out); std::runtime_error when
// files cannot be written.
void init_pki(const std::filesystem::path& dir, const PkiOptions& options);

// Issues (or re-issues) one node's directory from the CA in DIR/ca with the given validity. Used
// by init_pki; tests use it for expired certificates.
void issue_node(const std::filesystem::path& dir, const NodeIdentity& node,
                const std::string& organisation, const Validity& validity);

// The documents as written (unsigned), for reading and for tests.
std::string governance_xml();
std::string permissions_xml(const NodeIdentity& node, const std::string& organisation,
                            const std::string& not_before, const std::string& not_after);

// Directory of one node's documents under a PKI root: DIR/node_<id>.
std::filesystem::path node_dir(const std::filesystem::path& pki_dir, int node_id);

}  // namespace rths::security
