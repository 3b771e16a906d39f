#include "security/pki.h"

#include <openssl/pem.h>
#include <openssl/rand.h>
#include <openssl/x509v3.h>

#include <fstream>
#include <stdexcept>

#include "security/openssl.h"

namespace rths::security {
namespace fs = std::filesystem;

namespace {

constexpr long kCaDays = 3650;

bool valid_token(const std::string& text) {
  if (text.empty()) return false;
  for (const char c : text)
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_' || c == '.'))
      return false;
  return true;
}

ossl::Key new_key() {
  ossl::Key key(EVP_EC_gen("P-256"));
  ossl::require(key != nullptr, "EC P-256 key generation");
  return key;
}

void add_name_entry(X509_NAME* name, const char* field, const std::string& value) {
  ossl::require(X509_NAME_add_entry_by_txt(name, field, MBSTRING_ASC,
                                           reinterpret_cast<const unsigned char*>(value.c_str()),
                                           -1, -1, 0) == 1,
                std::string("certificate subject ") + field);
}

void add_extension(X509* cert, X509* issuer, int nid, const char* value) {
  X509V3_CTX ctx;
  X509V3_set_ctx_nodb(&ctx);
  X509V3_set_ctx(&ctx, issuer, cert, nullptr, nullptr, 0);
  X509_EXTENSION* ext = X509V3_EXT_conf_nid(nullptr, &ctx, nid, value);
  ossl::require(ext != nullptr, std::string("certificate extension ") + value);
  const int ok = X509_add_ext(cert, ext, -1);
  X509_EXTENSION_free(ext);
  ossl::require(ok == 1, std::string("certificate extension ") + value);
}

// A v3 certificate for `key`, subject `subject` (already filled), signed by issuer/issuer_key
// (itself when issuer is null).
ossl::Cert make_cert(EVP_PKEY* key, const std::vector<std::pair<const char*, std::string>>& subject,
                     X509* issuer, EVP_PKEY* issuer_key, const Validity& validity, bool ca) {
  ossl::Cert cert(X509_new());
  ossl::require(cert != nullptr, "X509_new");
  X509_set_version(cert.get(), 2);
  unsigned char serial[8];
  ossl::require(RAND_bytes(serial, sizeof serial) == 1, "certificate serial");
  serial[0] &= 0x7f;  // positive
  BIGNUM* bn = BN_bin2bn(serial, sizeof serial, nullptr);
  ossl::require(bn && BN_to_ASN1_INTEGER(bn, X509_get_serialNumber(cert.get())),
                "certificate serial");
  BN_free(bn);
  X509_gmtime_adj(X509_getm_notBefore(cert.get()), validity.not_before.count());
  X509_gmtime_adj(X509_getm_notAfter(cert.get()), validity.not_after.count());
  ossl::require(X509_set_pubkey(cert.get(), key) == 1, "certificate public key");
  X509_NAME* name = X509_get_subject_name(cert.get());
  for (const auto& [field, value] : subject) add_name_entry(name, field, value);
  X509* signer = issuer ? issuer : cert.get();
  ossl::require(X509_set_issuer_name(cert.get(), X509_get_subject_name(signer)) == 1,
                "certificate issuer");
  add_extension(cert.get(), signer, NID_basic_constraints, ca ? "critical,CA:TRUE" : "CA:FALSE");
  add_extension(cert.get(), signer, NID_key_usage,
                ca ? "critical,keyCertSign,cRLSign,digitalSignature"
                   : "critical,digitalSignature,keyAgreement");
  ossl::require(X509_sign(cert.get(), issuer_key ? issuer_key : key, EVP_sha256()) > 0,
                "certificate signature");
  return cert;
}

void write_text(const fs::path& file, const std::string& text, fs::perms perms) {
  std::ofstream out(file, std::ios::binary | std::ios::trunc);
  out << text;
  out.close();
  if (!out) throw std::runtime_error("cannot write " + file.string());
  fs::permissions(file, perms);
}

constexpr fs::perms kPublic =
    fs::perms::owner_read | fs::perms::owner_write | fs::perms::group_read | fs::perms::others_read;
constexpr fs::perms kSecret = fs::perms::owner_read | fs::perms::owner_write;

std::string cert_pem(X509* cert) {
  ossl::Bio bio(BIO_new(BIO_s_mem()));
  ossl::require(bio && PEM_write_bio_X509(bio.get(), cert) == 1, "PEM certificate");
  return ossl::bio_text(bio.get());
}

std::string key_pem(EVP_PKEY* key) {
  ossl::Bio bio(BIO_new(BIO_s_mem()));
  ossl::require(
      bio && PEM_write_bio_PrivateKey(bio.get(), key, nullptr, nullptr, 0, nullptr, nullptr) == 1,
      "PEM private key");
  return ossl::bio_text(bio.get());
}

// S/MIME (multipart/signed, detached, text) as `openssl smime -sign -text` writes it.
std::string smime_sign(const std::string& document, X509* signer, EVP_PKEY* key) {
  const int flags = PKCS7_DETACHED | PKCS7_TEXT | PKCS7_STREAM;
  ossl::Bio in(BIO_new_mem_buf(document.data(), static_cast<int>(document.size())));
  ossl::Pkcs7 p7(PKCS7_sign(signer, key, nullptr, in.get(), flags));
  ossl::require(p7 != nullptr, "S/MIME signature");
  ossl::Bio out(BIO_new(BIO_s_mem()));
  ossl::require(out && SMIME_write_PKCS7(out.get(), p7.get(), in.get(), flags) == 1,
                "S/MIME output");
  return ossl::bio_text(out.get());
}

struct LabCa {
  ossl::Cert cert;
  ossl::Key key;
};

LabCa load_ca(const fs::path& dir) {
  LabCa ca{ossl::read_cert(dir / "ca" / "ca_cert.pem"), ossl::read_key(dir / "ca" / "ca_key.pem")};
  if (!ca.cert || !ca.key)
    throw std::invalid_argument(
        (dir / "ca").string() +
        ": no lab CA (ca_cert.pem and ca_key.pem); run `rths pki init` first");
  return ca;
}

bool is_node_kind(const std::string& kind) {
  return kind == "substructure" || kind == "actuator_emulator" || kind == "controller";
}

}  // namespace

std::string subject_name(const NodeIdentity& node, const std::string& organisation) {
  return "CN=rths-node-" + std::to_string(node.node_id) + ",OU=" + node.kind + ",O=" + organisation;
}

void check_identity(const NodeIdentity& node) {
  if (node.node_id < 0)
    throw std::invalid_argument("node id " + std::to_string(node.node_id) + " < 0");
  if (node.node_id == kCoordinatorNodeId && node.kind != "coordinator")
    throw std::invalid_argument("node 0 is the coordinator, not '" + node.kind + "'");
  if (node.node_id != kCoordinatorNodeId && !is_node_kind(node.kind))
    throw std::invalid_argument("node " + std::to_string(node.node_id) + ": kind '" + node.kind +
                                "' is not substructure, actuator_emulator or controller");
}

fs::path node_dir(const fs::path& pki_dir, int node_id) {
  return pki_dir / ("node_" + std::to_string(node_id));
}

std::string governance_xml() {
  return R"(<?xml version="1.0" encoding="UTF-8"?>
<dds xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance" xsi:noNamespaceSchemaLocation="http://www.omg.org/spec/DDS-SECURITY/20170901/omg_shared_ca_governance.xsd">
  <domain_access_rules>
    <domain_rule>
      <domains><id_range><min>0</min><max>230</max></id_range></domains>
      <allow_unauthenticated_participants>false</allow_unauthenticated_participants>
      <enable_join_access_control>true</enable_join_access_control>
      <discovery_protection_kind>ENCRYPT</discovery_protection_kind>
      <liveliness_protection_kind>ENCRYPT</liveliness_protection_kind>
      <rtps_protection_kind>ENCRYPT</rtps_protection_kind>
      <topic_access_rules>
        <topic_rule>
          <topic_expression>*</topic_expression>
          <enable_discovery_protection>true</enable_discovery_protection>
          <enable_liveliness_protection>true</enable_liveliness_protection>
          <enable_read_access_control>true</enable_read_access_control>
          <enable_write_access_control>true</enable_write_access_control>
          <metadata_protection_kind>ENCRYPT</metadata_protection_kind>
          <data_protection_kind>ENCRYPT</data_protection_kind>
        </topic_rule>
      </topic_access_rules>
    </domain_rule>
  </domain_access_rules>
</dds>
)";
}

std::string permissions_xml(const NodeIdentity& node, const std::string& organisation,
                            const std::string& not_before, const std::string& not_after) {
  const bool coordinator = node.node_id == kCoordinatorNodeId;
  const std::string own = "*_node" + std::to_string(node.node_id);
  const std::string publish = coordinator ? "*_down" : own + "_up";
  const std::string subscribe = coordinator ? "*_up" : own + "_down";
  return R"(<?xml version="1.0" encoding="UTF-8"?>
<dds xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance" xsi:noNamespaceSchemaLocation="http://www.omg.org/spec/DDS-SECURITY/20170901/omg_shared_ca_permissions.xsd">
  <permissions>
    <grant name="rths_node_)" +
         std::to_string(node.node_id) + R"(">
      <subject_name>)" +
         subject_name(node, organisation) + R"(</subject_name>
      <validity><not_before>)" +
         not_before + "</not_before><not_after>" + not_after +
         R"(</not_after></validity>
      <allow_rule>
        <domains><id_range><min>0</min><max>230</max></id_range></domains>
        <publish><topics><topic>)" +
         publish + R"(</topic></topics></publish>
        <subscribe><topics><topic>)" +
         subscribe + R"(</topic></topics></subscribe>
      </allow_rule>
      <default>DENY</default>
    </grant>
  </permissions>
</dds>
)";
}

void issue_node(const fs::path& dir, const NodeIdentity& node, const std::string& organisation,
                const Validity& validity) {
  check_identity(node);
  const LabCa ca = load_ca(dir);
  const fs::path out = node_dir(dir, node.node_id);
  fs::create_directories(out);
  const ossl::Key key = new_key();
  const ossl::Cert cert = make_cert(
      key.get(),
      {{"O", organisation}, {"OU", node.kind}, {"CN", "rths-node-" + std::to_string(node.node_id)}},
      ca.cert.get(), ca.key.get(), validity, false);
  write_text(out / "identity_ca.pem", cert_pem(ca.cert.get()), kPublic);
  write_text(out / "cert.pem", cert_pem(cert.get()), kPublic);
  write_text(out / "key.pem", key_pem(key.get()), kSecret);
  write_text(out / "governance.p7s", smime_sign(governance_xml(), ca.cert.get(), ca.key.get()),
             kPublic);
  const std::string permissions =
      permissions_xml(node, organisation, ossl::iso_time(X509_get0_notBefore(cert.get())),
                      ossl::iso_time(X509_get0_notAfter(cert.get())));
  write_text(out / "permissions.xml", permissions, kPublic);
  write_text(out / "permissions.p7s", smime_sign(permissions, ca.cert.get(), ca.key.get()),
             kPublic);
}

void init_pki(const fs::path& dir, const PkiOptions& options) {
  if (!valid_token(options.organisation))
    throw std::invalid_argument("organisation '" + options.organisation +
                                "': use letters, digits, '-', '_' or '.'");
  if (options.days < 1) throw std::invalid_argument("--days must be >= 1");
  std::vector<NodeIdentity> nodes = options.nodes;
  bool has_coordinator = false;
  for (const NodeIdentity& node : nodes) {
    check_identity(node);
    has_coordinator |= node.node_id == kCoordinatorNodeId;
    int same = 0;
    for (const NodeIdentity& other : nodes) same += other.node_id == node.node_id;
    if (same > 1)
      throw std::invalid_argument("node " + std::to_string(node.node_id) + " given twice");
  }
  if (!has_coordinator) nodes.insert(nodes.begin(), {kCoordinatorNodeId, "coordinator"});
  if (fs::exists(dir / "ca" / "ca_key.pem"))
    throw std::invalid_argument(dir.string() + " already holds a lab CA; use a new directory");

  fs::create_directories(dir / "ca");
  fs::permissions(dir / "ca", fs::perms::owner_all);
  const ossl::Key ca_key = new_key();
  const ossl::Cert ca_cert = make_cert(
      ca_key.get(), {{"O", options.organisation}, {"CN", "rths-lab-ca"}}, nullptr, nullptr,
      {std::chrono::seconds(-3600), std::chrono::seconds(kCaDays * 86400)}, true);
  write_text(dir / "ca" / "ca_cert.pem", cert_pem(ca_cert.get()), kPublic);
  write_text(dir / "ca" / "ca_key.pem", key_pem(ca_key.get()), kSecret);
  write_text(dir / "governance.xml", governance_xml(), kPublic);
  const Validity validity{std::chrono::seconds(-3600),
                          std::chrono::seconds(static_cast<long long>(options.days) * 86400)};
  for (const NodeIdentity& node : nodes) issue_node(dir, node, options.organisation, validity);
}

}  // namespace rths::security
