// The per-site Cyclone DDS configuration: what it says (interface, no multicast, unicast peers,
// participant index), that Cyclone DDS itself accepts it (a real domain and participant, DDS
// domain 94), and its refusals.
#include "deploy/dds_config.h"

#include <dds/dds.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>

namespace rths::deploy {
namespace {

DdsSiteConfig loopback() { return {"lo", {"127.0.0.1", "10.0.0.2"}, 40}; }

TEST(DdsConfig, NamesTheInterfaceEveryPeerAndNoMulticast) {
  const std::string xml = dds_config_xml(loopback());
  EXPECT_NE(xml.find("<NetworkInterface name=\"lo\"/>"), std::string::npos) << xml;
  EXPECT_NE(xml.find("<AllowMulticast>false</AllowMulticast>"), std::string::npos);
  EXPECT_NE(xml.find("<ParticipantIndex>auto</ParticipantIndex>"), std::string::npos);
  EXPECT_NE(xml.find("<MaxAutoParticipantIndex>40</MaxAutoParticipantIndex>"), std::string::npos);
  EXPECT_NE(xml.find("<Peer address=\"127.0.0.1\"/>"), std::string::npos);
  EXPECT_NE(xml.find("<Peer address=\"10.0.0.2\"/>"), std::string::npos);
}

TEST(DdsConfig, CycloneDdsAcceptsItForARealParticipant) {
  const std::string xml = dds_config_xml({"lo", {"127.0.0.1"}, 32});
  const dds_entity_t domain = dds_create_domain(94, xml.c_str());
  ASSERT_GT(domain, 0) << dds_strretcode(domain);
  const dds_entity_t participant = dds_create_participant(94, nullptr, nullptr);
  EXPECT_GT(participant, 0) << dds_strretcode(participant);
  dds_delete(domain);
}

TEST(DdsConfig, WriteReturnsAFileUriOfTheXml) {
  const auto file = std::filesystem::temp_directory_path() / "rths_dds_config_test.xml";
  const std::string uri = write_dds_config(loopback(), file);
  EXPECT_EQ(uri, "file://" + std::filesystem::absolute(file).string());
  std::ifstream in(file);
  std::stringstream text;
  text << in.rdbuf();
  EXPECT_EQ(text.str(), dds_config_xml(loopback()));
  std::filesystem::remove(file);
}

TEST(DdsConfig, RefusesWhatWouldMisconfigureASite) {
  EXPECT_THROW(dds_config_xml({"", {"127.0.0.1"}, 32}), std::invalid_argument);
  EXPECT_THROW(dds_config_xml({"eth0\"/><x", {"127.0.0.1"}, 32}), std::invalid_argument);
  EXPECT_THROW(dds_config_xml({"lo", {}, 32}), std::invalid_argument);
  EXPECT_THROW(dds_config_xml({"lo", {"lab-b.example.org"}, 32}), std::invalid_argument);
  EXPECT_THROW(dds_config_xml({"lo", {"127.0.0.1"}, 0}), std::invalid_argument);
  EXPECT_THROW(write_dds_config(loopback(), "/nonexistent-dir/x.xml"), std::runtime_error);
}

}  // namespace
}  // namespace rths::deploy
