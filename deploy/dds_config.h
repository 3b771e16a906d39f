#pragma once
// Cyclone DDS configuration for a participant at one site: discovery by unicast to every site's
// address (no multicast: a veth bridge carries it, but real wide-area links between labs do not,
// and unicast keeps the emulation honest), bound to the site's interface.
//
//   <Interfaces><NetworkInterface name="eth0"/></Interfaces>, AllowMulticast false,
//   ParticipantIndex auto, MaxAutoParticipantIndex >= 32 (several processes per site),
//   one <Peer address="..."/> per site (itself included, for processes at the same site).
// The XML is what CYCLONEDDS_URI points at (file://PATH) in each node's environment.

#include <filesystem>
#include <string>
#include <vector>

namespace rths::deploy {

struct DdsSiteConfig {
  std::string interface;                // network interface name inside the site, e.g. "eth0"
  std::vector<std::string> peers;       // IPv4 addresses of every site
  int max_auto_participant_index = 32;  // >= number of DDS processes per site
};

// Throws std::invalid_argument on an interface that is not an interface name (1-15 of
// [A-Za-z0-9_.:-]), no peers, a peer that is not IPv4 or an index below 1.
std::string dds_config_xml(const DdsSiteConfig& config);

// Writes the XML; returns the CYCLONEDDS_URI value for it ("file://" + absolute path).
std::string write_dds_config(const DdsSiteConfig& config, const std::filesystem::path& file);

}  // namespace rths::deploy
