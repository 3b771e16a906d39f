// Start-up check of a node's documents: every refusal names the file and the reason.
#include "security/check.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "support.h"

namespace rths::security {
namespace {

namespace fs = std::filesystem;
using ::testing::AllOf;
using ::testing::HasSubstr;

std::string refusal(const fs::path& dir, int node_id) {
  try {
    check_node_security(dir, node_id);
  } catch (const SecurityError& e) {
    return e.what();
  }
  return "accepted";
}

TEST(Check, AcceptsEveryNodeOfAFreshLab) {
  const fs::path dir = test::make_lab("accepts");
  for (const int id : {0, 1, 2}) {
    const NodeSecurityFiles files = check_node_security(node_dir(dir, id), id);
    EXPECT_EQ(files.certificate, node_dir(dir, id) / "cert.pem");
    EXPECT_THAT(files.subject, HasSubstr("CN=rths-node-" + std::to_string(id)));
  }
}

TEST(Check, RefusesAnExpiredCertificate) {
  const fs::path dir = test::make_lab("expired");
  issue_node(dir, {2, "actuator_emulator"}, "rths-lab",
             {std::chrono::seconds(-10 * 86400), std::chrono::seconds(-86400)});
  EXPECT_THAT(refusal(node_dir(dir, 2), 2),
              AllOf(HasSubstr((node_dir(dir, 2) / "cert.pem").string()), HasSubstr("expired")));
}

TEST(Check, RefusesACertificateThatIsNotYetValid) {
  const fs::path dir = test::make_lab("not_yet");
  issue_node(dir, {1, "substructure"}, "rths-lab",
             {std::chrono::seconds(86400), std::chrono::seconds(2 * 86400)});
  EXPECT_THAT(refusal(node_dir(dir, 1), 1), HasSubstr("not yet valid"));
}

TEST(Check, RefusesACertificateNotSignedByTheLabCa) {
  const fs::path dir = test::make_lab("unsigned");
  const fs::path stranger = test::make_lab("unsigned_stranger");
  fs::copy_file(node_dir(stranger, 1) / "cert.pem", node_dir(dir, 1) / "cert.pem",
                fs::copy_options::overwrite_existing);
  EXPECT_THAT(refusal(node_dir(dir, 1), 1),
              AllOf(HasSubstr("cert.pem"), HasSubstr("not signed by the lab CA")));
}

TEST(Check, RefusesAnotherNodesCertificate) {
  const fs::path dir = test::make_lab("other_node");
  EXPECT_THAT(refusal(node_dir(dir, 1), 2),
              AllOf(HasSubstr("cert.pem"), HasSubstr("is for rths-node-1, not for node 2")));
}

TEST(Check, RefusesAKeyThatDoesNotMatchTheCertificate) {
  const fs::path dir = test::make_lab("key_mismatch");
  fs::copy_file(node_dir(dir, 2) / "key.pem", node_dir(dir, 1) / "key.pem",
                fs::copy_options::overwrite_existing);
  EXPECT_THAT(refusal(node_dir(dir, 1), 1),
              AllOf(HasSubstr("key.pem"), HasSubstr("does not match cert.pem")));
}

TEST(Check, RefusesMissingFilesAndDirectories) {
  const fs::path dir = test::make_lab("missing");
  EXPECT_THAT(refusal(dir / "node_9", 9), HasSubstr("not a directory"));
  fs::remove(node_dir(dir, 1) / "permissions.p7s");
  EXPECT_THAT(refusal(node_dir(dir, 1), 1),
              AllOf(HasSubstr("permissions.p7s"), HasSubstr("missing")));
}

TEST(Check, RefusesAnUnsignedOrTamperedDocument) {
  const fs::path dir = test::make_lab("tampered");
  // The plain XML where the signed document belongs.
  fs::copy_file(node_dir(dir, 1) / "permissions.xml", node_dir(dir, 1) / "permissions.p7s",
                fs::copy_options::overwrite_existing);
  EXPECT_THAT(refusal(node_dir(dir, 1), 1),
              AllOf(HasSubstr("permissions.p7s"), HasSubstr("not an S/MIME signed document")));
  // A grant widened after signing.
  std::string text = test::slurp(node_dir(dir, 2) / "permissions.p7s");
  const auto at = text.find("<topic>*_node2_up</topic>");
  ASSERT_NE(at, std::string::npos);
  text.replace(at, 25, "<topic>*_node1_up</topic>");
  std::ofstream(node_dir(dir, 2) / "permissions.p7s") << text;
  EXPECT_THAT(refusal(node_dir(dir, 2), 2), HasSubstr("signature does not verify"));
}

TEST(Check, RefusesADocumentSignedByAnotherCa) {
  const fs::path dir = test::make_lab("other_ca_doc");
  const fs::path stranger = test::make_lab("other_ca_doc_stranger");
  fs::copy_file(node_dir(stranger, 0) / "governance.p7s", node_dir(dir, 0) / "governance.p7s",
                fs::copy_options::overwrite_existing);
  EXPECT_THAT(refusal(node_dir(dir, 0), 0),
              AllOf(HasSubstr("governance.p7s"), HasSubstr("signature does not verify")));
}

TEST(Check, RefusesMalformedXmlEvenWhenProperlySigned) {
  const fs::path dir = test::make_lab("malformed");
  test::sign_with_openssl(dir, "<dds><domain_access_rules><domain_rule>",
                          node_dir(dir, 0) / "governance.p7s");
  EXPECT_THAT(refusal(node_dir(dir, 0), 0),
              AllOf(HasSubstr("governance.p7s"), HasSubstr("not well-formed XML")));
  test::sign_with_openssl(dir, "<html><permissions/></html>", node_dir(dir, 1) / "permissions.p7s");
  EXPECT_THAT(refusal(node_dir(dir, 1), 1), HasSubstr("root element is not <dds>"));
  // Well-formed, signed, but without this node's grant.
  test::sign_with_openssl(dir, permissions_xml({2, "actuator_emulator"}, "rths-lab", "x", "y"),
                          node_dir(dir, 1) / "permissions.p7s");
  EXPECT_THAT(refusal(node_dir(dir, 1), 1),
              HasSubstr("no <grant> for CN=rths-node-1,OU=substructure,O=rths-lab"));
}

TEST(Check, DocumentsSignedWithTheOpensslCommandLineAreAccepted) {
  const fs::path dir = test::make_lab("openssl_signed");
  test::sign_with_openssl(dir, governance_xml(), node_dir(dir, 2) / "governance.p7s");
  EXPECT_NO_THROW(check_node_security(node_dir(dir, 2), 2));
}

// A signed governance that does not cover the run's domain is refused by the launcher's check,
// before anything starts, naming the file, what it covers and the run's domain.
TEST(Check, TheLabCheckRefusesAGovernanceThatDoesNotCoverTheRunsDomain) {
  const fs::path dir = test::make_lab("governance_domains");
  EXPECT_NO_THROW(check_lab_security(dir, {0, 1, 2}, 7));
  std::string narrow = governance_xml();
  const std::string wide = "<id_range><min>0</min><max>230</max></id_range>";
  narrow.replace(narrow.find(wide), wide.size(),
                 "<id>3</id><id_range><min>10</min><max>12</max></id_range>");
  test::sign_with_openssl(dir, narrow, node_dir(dir, 2) / "governance.p7s");
  EXPECT_NO_THROW(check_lab_security(dir, {0, 1, 2}, 11));
  EXPECT_EQ(check_node_security(node_dir(dir, 2), 2).governance_domains.size(), 2u);
  try {
    check_lab_security(dir, {0, 1, 2}, 7);
    FAIL() << "accepted";
  } catch (const SecurityError& e) {
    EXPECT_THAT(std::string(e.what()),
                AllOf(HasSubstr("node_2/governance.p7s"), HasSubstr("cover 3, 10-12"),
                      HasSubstr("not the run's DDS domain 7")));
  }
}

TEST(Check, PropertiesPointCycloneAtThePluginsAndTheFiles) {
  const fs::path dir = test::make_lab("properties");
  const auto properties = participant_properties(check_node_security(node_dir(dir, 1), 1));
  const auto value = [&](const std::string& name) {
    for (const auto& [n, v] : properties)
      if (n == name) return v;
    return std::string();
  };
  EXPECT_EQ(value("dds.sec.auth.identity_certificate"),
            "file:" + (node_dir(dir, 1) / "cert.pem").string());
  EXPECT_EQ(value("dds.sec.access.permissions"),
            "file:" + (node_dir(dir, 1) / "permissions.p7s").string());
  EXPECT_THAT(value("dds.sec.auth.library.path"), HasSubstr("dds_security_auth"));
  if (!plugin_directory().empty())
    EXPECT_TRUE(fs::is_regular_file(value("dds.sec.crypto.library.path")));
}

}  // namespace
}  // namespace rths::security
