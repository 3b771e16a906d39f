#pragma once
// Start-up check of one node's DDS Security documents (a node directory written by
// `rths pki init`, see security/pki.h), done before the node creates its DDS participant, so a
// bad document stops the node before any message is sent -- and never falls back to an unsecured
// run. Then the Cyclone DDS participant properties that switch security on with those files.
//
// check_node_security(DIR, node_id) verifies, in this order, and throws SecurityError naming the
// file and the reason at the first failure:
//   identity_ca.pem   readable PEM certificate (the lab CA: identity and permissions CA)
//   cert.pem          readable; signed by that CA; inside its validity period (not expired, not
//                     yet valid); its subject's CN is "rths-node-<node_id>" (not another node's)
//   key.pem           readable private key that matches cert.pem
//   governance.p7s    S/MIME signed by the CA; content well-formed XML <dds><domain_access_rules>
//   permissions.p7s   S/MIME signed by the CA; content well-formed XML <dds><permissions> with a
//                     <grant> whose <subject_name> is cert.pem's subject
// SecurityError is a std::invalid_argument: the programs exit 2 (bad input).

#include <filesystem>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace rths::security {

struct SecurityError : std::invalid_argument {
  using std::invalid_argument::invalid_argument;
};

struct DomainRange {
  int min = 0, max = 0;  // inclusive
};

struct NodeSecurityFiles {
  std::filesystem::path identity_ca, certificate, private_key, governance, permissions;
  std::string subject;                          // cert.pem's subject, "CN=...,OU=...,O=..."
  std::vector<DomainRange> governance_domains;  // the domain ids its domain rules cover
};

NodeSecurityFiles check_node_security(const std::filesystem::path& node_dir, int node_id);

// For launchers, before they start anything: check_node_security of every id's folder
// (pki_dir/node_<id>) under the `rths pki init` directory, and (domain >= 0) that each folder's
// governance covers the run's DDS domain (else SecurityError naming governance.p7s, the
// domains it covers and the run's).
void check_lab_security(const std::filesystem::path& pki_dir, const std::vector<int>& node_ids,
                        int domain = -1);

// The arguments that hand node `node_id` its folder: {"--security", pki_dir/node_<id>}, or {}
// when pki_dir is empty (security off).
std::vector<std::string> security_arguments(const std::filesystem::path& pki_dir, int node_id);

// Name/value pairs for the participant's QoS (dds_qset_prop): the three built-in plugin libraries
// (full paths where this build found them, else bare names for the loader's search path) and
// "file:" URIs of the documents.
std::vector<std::pair<std::string, std::string>> participant_properties(
    const NodeSecurityFiles& files);

// Where Cyclone DDS's security plugins live on this machine ("" = leave it to the loader).
std::string plugin_directory();

}  // namespace rths::security
