// The lab PKI: layout, subjects, permissions per node kind, and what the openssl command line
// thinks of the result (an independent verifier of the certificates and signatures).
#include "security/pki.h"

#include <gtest/gtest.h>

#include "support.h"

namespace rths::security {
namespace {

namespace fs = std::filesystem;

int run(const std::string& command) { return std::system((command + " >/dev/null 2>&1").c_str()); }

TEST(Pki, WritesOneSelfContainedDirectoryPerNodeAndKeepsTheCaKeyApart) {
  const fs::path dir = test::make_lab("layout");
  for (const int id : {0, 1, 2}) {
    for (const char* file : {"identity_ca.pem", "cert.pem", "key.pem", "governance.p7s",
                             "permissions.xml", "permissions.p7s"})
      EXPECT_TRUE(fs::is_regular_file(node_dir(dir, id) / file)) << id << " " << file;
    EXPECT_FALSE(fs::exists(node_dir(dir, id) / "ca_key.pem"));
    EXPECT_EQ(fs::status(node_dir(dir, id) / "key.pem").permissions() & fs::perms::others_read,
              fs::perms::none);
  }
  EXPECT_EQ(fs::status(dir / "ca" / "ca_key.pem").permissions() & fs::perms::group_read,
            fs::perms::none);
}

TEST(Pki, OpensslVerifiesEveryCertificateAndSignatureAgainstTheLabCa) {
  const fs::path dir = test::make_lab("openssl");
  const std::string ca = (dir / "ca" / "ca_cert.pem").string();
  for (const int id : {0, 1, 2}) {
    const fs::path node = node_dir(dir, id);
    EXPECT_EQ(run("openssl verify -CAfile " + ca + " " + (node / "cert.pem").string()), 0) << id;
    for (const char* doc : {"governance.p7s", "permissions.p7s"})
      EXPECT_EQ(run("openssl smime -verify -text -CAfile " + ca + " -in " + (node / doc).string() +
                    " -out /dev/null"),
                0)
          << id << " " << doc;
  }
  // And a second lab's CA does not vouch for this lab's node.
  const fs::path other = test::make_lab("openssl_other");
  EXPECT_NE(run("openssl verify -CAfile " + (other / "ca" / "ca_cert.pem").string() + " " +
                (node_dir(dir, 1) / "cert.pem").string()),
            0);
}

// The coordinator one direction on every node's topics; node N its own two topics only.
TEST(Pki, EachNodeMayOnlyUseItsOwnTopics) {
  const std::string coordinator = permissions_xml({0, "coordinator"}, "lab", "a", "b");
  EXPECT_NE(coordinator.find("<publish><topics><topic>*_down</topic>"), std::string::npos);
  EXPECT_NE(coordinator.find("<subscribe><topics><topic>*_up</topic>"), std::string::npos);
  for (const NodeIdentity node :
       {NodeIdentity{1, "substructure"}, NodeIdentity{2, "actuator_emulator"}}) {
    const std::string text = permissions_xml(node, "lab", "a", "b");
    const std::string own = "*_node" + std::to_string(node.node_id);
    EXPECT_NE(text.find("<publish><topics><topic>" + own + "_up</topic></topics>"),
              std::string::npos);
    EXPECT_NE(text.find("<subscribe><topics><topic>" + own + "_down</topic></topics>"),
              std::string::npos);
    EXPECT_EQ(text.find("<topic>*_up</topic>"), std::string::npos);
    EXPECT_EQ(text.find("<topic>*_down</topic>"), std::string::npos);
    EXPECT_EQ(text.find("_down</topic></topics></publish>"), std::string::npos);
    EXPECT_NE(text.find("<subject_name>" + subject_name(node, "lab") + "</subject_name>"),
              std::string::npos);
    EXPECT_NE(text.find("<default>DENY</default>"), std::string::npos);
  }
  const std::string governance = governance_xml();
  EXPECT_NE(governance.find("<allow_unauthenticated_participants>false"), std::string::npos);
  EXPECT_NE(governance.find("<enable_join_access_control>true"), std::string::npos);
  EXPECT_NE(governance.find("<enable_write_access_control>true"), std::string::npos);
}

TEST(Pki, SubjectNamesTheNodeAndItsKind) {
  EXPECT_EQ(subject_name({2, "actuator_emulator"}, "lab-x"),
            "CN=rths-node-2,OU=actuator_emulator,O=lab-x");
}

TEST(Pki, RefusesBadOptionsAndASecondInitInTheSameDirectory) {
  const fs::path dir = test::make_lab("twice");
  EXPECT_THROW(init_pki(dir, {}), std::invalid_argument);
  const fs::path fresh = test::fresh_dir("bad_options");
  EXPECT_THROW(init_pki(fresh, {"bad org,CN=x", 365, {}}), std::invalid_argument);
  EXPECT_THROW(init_pki(fresh, {"lab", 0, {}}), std::invalid_argument);
  EXPECT_THROW(init_pki(fresh, {"lab", 30, {{1, "robot"}}}), std::invalid_argument);
  EXPECT_THROW(init_pki(fresh, {"lab", 30, {{0, "substructure"}}}), std::invalid_argument);
  EXPECT_THROW(init_pki(fresh, {"lab", 30, {{1, "substructure"}, {1, "substructure"}}}),
               std::invalid_argument);
  EXPECT_FALSE(fs::exists(fresh / "ca"));
}

TEST(Pki, CoordinatorIsAddedWhenNotListed) {
  const fs::path dir = test::fresh_dir("coordinator_added");
  init_pki(dir, {"lab", 10, {{3, "substructure"}}});
  EXPECT_TRUE(fs::exists(node_dir(dir, 0) / "cert.pem"));
  EXPECT_TRUE(fs::exists(node_dir(dir, 3) / "cert.pem"));
}

}  // namespace
}  // namespace rths::security
