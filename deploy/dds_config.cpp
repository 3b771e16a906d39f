#include "deploy/dds_config.h"

#include <fstream>
#include <regex>
#include <stdexcept>

namespace rths::deploy {

std::string dds_config_xml(const DdsSiteConfig& config) {
  if (config.interface.empty()) throw std::invalid_argument("DDS config: empty interface name");
  // Linux interface names; anything else would also break the XML it is written into.
  if (!std::regex_match(config.interface, std::regex(R"([A-Za-z0-9_.:-]{1,15})")))
    throw std::invalid_argument("DDS config: interface '" + config.interface +
                                "' is not a network interface name");
  if (config.peers.empty()) throw std::invalid_argument("DDS config: no peers");
  if (config.max_auto_participant_index < 1) {
    throw std::invalid_argument("DDS config: max_auto_participant_index must be >= 1");
  }
  const std::regex ipv4(R"(\d{1,3}\.\d{1,3}\.\d{1,3}\.\d{1,3})");
  std::string xml =
      "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
      "<CycloneDDS xmlns=\"https://cdds.io/config\">\n"
      "  <Domain Id=\"any\">\n"
      "    <General>\n"
      "      <Interfaces><NetworkInterface name=\"" +
      config.interface +
      "\"/></Interfaces>\n"
      "      <AllowMulticast>false</AllowMulticast>\n"
      "    </General>\n"
      "    <Discovery>\n"
      "      <ParticipantIndex>auto</ParticipantIndex>\n"
      "      <MaxAutoParticipantIndex>" +
      std::to_string(config.max_auto_participant_index) +
      "</MaxAutoParticipantIndex>\n"
      "      <Peers>\n";
  for (const auto& peer : config.peers) {
    if (!std::regex_match(peer, ipv4)) {
      throw std::invalid_argument("DDS config: peer '" + peer + "' is not an IPv4 address");
    }
    xml += "        <Peer address=\"" + peer + "\"/>\n";
  }
  xml +=
      "      </Peers>\n"
      "    </Discovery>\n"
      "  </Domain>\n"
      "</CycloneDDS>\n";
  return xml;
}

std::string write_dds_config(const DdsSiteConfig& config, const std::filesystem::path& file) {
  const auto xml = dds_config_xml(config);
  std::ofstream out(file);
  out << xml;
  if (!out) throw std::runtime_error("cannot write DDS config " + file.string());
  return "file://" + std::filesystem::absolute(file).string();
}

}  // namespace rths::deploy
