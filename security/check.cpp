#include "security/check.h"

#include <libxml/parser.h>
#include <libxml/tree.h>
#include <openssl/pem.h>
#include <openssl/x509v3.h>

#include <limits>
#include <memory>

#include "security/openssl.h"
#include "security/pki.h"

namespace rths::security {
namespace fs = std::filesystem;

namespace {

[[noreturn]] void refuse(const fs::path& file, const std::string& reason) {
  throw SecurityError("DDS Security: " + file.string() + ": " + reason);
}

fs::path existing(const fs::path& dir, const char* name) {
  const fs::path file = dir / name;
  if (!fs::is_regular_file(file)) refuse(file, "missing");
  return file;
}

std::string subject_of(X509* cert) {
  // Cyclone compares subjects as comma/slash separated key=value sets; ours hold no separators.
  std::string text;
  const X509_NAME* name = X509_get_subject_name(cert);
  for (int i = X509_NAME_entry_count(name) - 1; i >= 0; --i) {
    const X509_NAME_ENTRY* entry = X509_NAME_get_entry(name, i);
    const char* field = OBJ_nid2sn(OBJ_obj2nid(X509_NAME_ENTRY_get_object(entry)));
    const ASN1_STRING* value = X509_NAME_ENTRY_get_data(entry);
    if (!text.empty()) text += ",";
    text += std::string(field) + "=" +
            std::string(reinterpret_cast<const char*>(ASN1_STRING_get0_data(value)),
                        static_cast<std::size_t>(ASN1_STRING_length(value)));
  }
  return text;
}

std::string common_name(X509* cert) {
  char cn[256] = {};
  const int n =
      X509_NAME_get_text_by_NID(X509_get_subject_name(cert), NID_commonName, cn, sizeof cn);
  return n > 0 ? std::string(cn, static_cast<std::size_t>(n)) : std::string();
}

void verify_certificate(const fs::path& file, X509* cert, X509* ca) {
  ossl::Store store(X509_STORE_new());
  ossl::StoreCtx ctx(X509_STORE_CTX_new());
  ossl::require(store && ctx && X509_STORE_add_cert(store.get(), ca) == 1 &&
                    X509_STORE_CTX_init(ctx.get(), store.get(), cert, nullptr) == 1,
                "certificate store");
  if (X509_verify_cert(ctx.get()) == 1) return;
  const int error = X509_STORE_CTX_get_error(ctx.get());
  std::string reason = X509_verify_cert_error_string(error);
  if (error == X509_V_ERR_CERT_HAS_EXPIRED)
    reason += " (not after " + ossl::iso_time(X509_get0_notAfter(cert)) + " UTC)";
  else if (error == X509_V_ERR_CERT_NOT_YET_VALID)
    reason += " (not before " + ossl::iso_time(X509_get0_notBefore(cert)) + " UTC)";
  else if (error == X509_V_ERR_UNABLE_TO_GET_ISSUER_CERT_LOCALLY ||
           error == X509_V_ERR_DEPTH_ZERO_SELF_SIGNED_CERT ||
           error == X509_V_ERR_CERT_SIGNATURE_FAILURE)
    reason = "not signed by the lab CA (" + reason + ")";
  refuse(file, reason);
}

// The signed content of an S/MIME document, verified against the CA.
std::string verified_content(const fs::path& file, X509* ca) {
  ossl::Bio in(BIO_new_file(file.c_str(), "r"));
  if (!in) refuse(file, "cannot be read");
  BIO* content_raw = nullptr;
  ossl::Pkcs7 p7(SMIME_read_PKCS7(in.get(), &content_raw));
  ossl::Bio content(content_raw);
  if (!p7) refuse(file, "not an S/MIME signed document (" + ossl::last_error() + ")");
  ossl::Store store(X509_STORE_new());
  ossl::Bio out(BIO_new(BIO_s_mem()));
  ossl::require(store && out && X509_STORE_add_cert(store.get(), ca) == 1, "certificate store");
  if (PKCS7_verify(p7.get(), nullptr, store.get(), content.get(), out.get(), PKCS7_TEXT) != 1)
    refuse(file, "signature does not verify against the lab CA (" + ossl::last_error() + ")");
  return ossl::bio_text(out.get());
}

struct XmlDocDeleter {
  void operator()(xmlDoc* doc) const { xmlFreeDoc(doc); }
};
using XmlDoc = std::unique_ptr<xmlDoc, XmlDocDeleter>;

XmlDoc parse_xml(const fs::path& file, const std::string& text) {
  XmlDoc doc(xmlReadMemory(text.data(), static_cast<int>(text.size()), file.c_str(), nullptr,
                           XML_PARSE_NONET | XML_PARSE_NOERROR | XML_PARSE_NOWARNING));
  if (!doc) {
    const xmlError* error = xmlGetLastError();
    refuse(file, std::string("signed content is not well-formed XML") +
                     (error && error->message ? ": line " + std::to_string(error->line) + ": " +
                                                    std::string(error->message)
                                              : std::string()));
  }
  const xmlNode* root = xmlDocGetRootElement(doc.get());
  if (!root || std::string(reinterpret_cast<const char*>(root->name)) != "dds")
    refuse(file, "signed content's root element is not <dds>");
  return doc;
}

const xmlNode* child(const xmlNode* node, const char* name) {
  for (const xmlNode* c = node ? node->children : nullptr; c; c = c->next)
    if (c->type == XML_ELEMENT_NODE && std::string(reinterpret_cast<const char*>(c->name)) == name)
      return c;
  return nullptr;
}

std::string text_of(const xmlNode* node) {
  xmlChar* content = xmlNodeGetContent(node);
  std::string text = content ? reinterpret_cast<const char*>(content) : "";
  xmlFree(content);
  const auto first = text.find_first_not_of(" \t\r\n");
  const auto last = text.find_last_not_of(" \t\r\n");
  return first == std::string::npos ? "" : text.substr(first, last - first + 1);
}

bool is_element(const xmlNode* node, const char* name) {
  return node->type == XML_ELEMENT_NODE &&
         std::string(reinterpret_cast<const char*>(node->name)) == name;
}

int domain_id_of(const fs::path& file, const xmlNode* node) {
  const std::string text = text_of(node);
  try {
    std::size_t used = 0;
    const int id = std::stoi(text, &used);
    if (used == text.size() && id >= 0) return id;
  } catch (const std::exception&) {}
  refuse(file, "domain id '" + text + "' is not a number >= 0");
}

// The domain ids a <domains> element covers: <id>N</id> and <id_range><min>A</min><max>B</max>
// (no <max>: every id from A on).
void add_domains(const fs::path& file, const xmlNode* domains, std::vector<DomainRange>& out) {
  for (const xmlNode* d = domains ? domains->children : nullptr; d; d = d->next) {
    if (is_element(d, "id")) {
      const int id = domain_id_of(file, d);
      out.push_back({id, id});
    } else if (is_element(d, "id_range")) {
      const xmlNode* min = child(d, "min");
      const xmlNode* max = child(d, "max");
      out.push_back({min ? domain_id_of(file, min) : 0,
                     max ? domain_id_of(file, max) : std::numeric_limits<int>::max()});
    }
  }
}

std::vector<DomainRange> check_governance(const fs::path& file, X509* ca) {
  const XmlDoc doc = parse_xml(file, verified_content(file, ca));
  const xmlNode* rules = child(xmlDocGetRootElement(doc.get()), "domain_access_rules");
  if (!child(rules, "domain_rule")) refuse(file, "no <domain_access_rules><domain_rule>");
  std::vector<DomainRange> domains;
  for (const xmlNode* rule = rules->children; rule; rule = rule->next)
    if (is_element(rule, "domain_rule")) add_domains(file, child(rule, "domains"), domains);
  return domains;
}

void check_permissions(const fs::path& file, X509* ca, const std::string& subject) {
  const XmlDoc doc = parse_xml(file, verified_content(file, ca));
  const xmlNode* permissions = child(xmlDocGetRootElement(doc.get()), "permissions");
  if (!permissions) refuse(file, "no <permissions> element");
  for (const xmlNode* grant = permissions->children; grant; grant = grant->next) {
    if (grant->type != XML_ELEMENT_NODE ||
        std::string(reinterpret_cast<const char*>(grant->name)) != "grant")
      continue;
    if (text_of(child(grant, "subject_name")) != subject) continue;
    if (!child(grant, "validity") || !child(grant, "allow_rule"))
      refuse(file, "the grant for " + subject + " lacks <validity> or <allow_rule>");
    return;
  }
  refuse(file, "no <grant> for " + subject);
}

}  // namespace

NodeSecurityFiles check_node_security(const fs::path& dir, int node_id) {
  if (!fs::is_directory(dir)) refuse(dir, "not a directory");
  NodeSecurityFiles files;
  files.identity_ca = existing(dir, "identity_ca.pem");
  files.certificate = existing(dir, "cert.pem");
  files.private_key = existing(dir, "key.pem");
  files.governance = existing(dir, "governance.p7s");
  files.permissions = existing(dir, "permissions.p7s");

  const ossl::Cert ca = ossl::read_cert(files.identity_ca);
  if (!ca) refuse(files.identity_ca, "not a PEM certificate (" + ossl::last_error() + ")");
  const ossl::Cert cert = ossl::read_cert(files.certificate);
  if (!cert) refuse(files.certificate, "not a PEM certificate (" + ossl::last_error() + ")");
  verify_certificate(files.certificate, cert.get(), ca.get());
  const std::string expected_cn = "rths-node-" + std::to_string(node_id);
  if (common_name(cert.get()) != expected_cn)
    refuse(files.certificate, "certificate is for " + common_name(cert.get()) + ", not for node " +
                                  std::to_string(node_id) + " (" + expected_cn + ")");
  const ossl::Key key = ossl::read_key(files.private_key);
  if (!key) refuse(files.private_key, "not a PEM private key (" + ossl::last_error() + ")");
  if (X509_check_private_key(cert.get(), key.get()) != 1) {
    ossl::last_error();
    refuse(files.private_key, "does not match " + files.certificate.filename().string());
  }
  files.subject = subject_of(cert.get());
  files.governance_domains = check_governance(files.governance, ca.get());
  check_permissions(files.permissions, ca.get(), files.subject);
  return files;
}

void check_lab_security(const fs::path& pki_dir, const std::vector<int>& node_ids, int domain) {
  for (const int id : node_ids) {
    const NodeSecurityFiles files = check_node_security(node_dir(pki_dir, id), id);
    if (domain < 0) continue;
    std::string covered;
    for (const DomainRange& r : files.governance_domains) {
      if (domain >= r.min && domain <= r.max) {
        covered.clear();
        break;
      }
      if (!covered.empty()) covered.append(", ");
      covered.append(std::to_string(r.min));
      if (r.max != r.min) covered.append("-");
      if (r.max != r.min && r.max != std::numeric_limits<int>::max())
        covered.append(std::to_string(r.max));
    }
    if (!covered.empty() || files.governance_domains.empty())
      refuse(files.governance, "its domain rules cover " +
                                   (covered.empty() ? std::string("no domain") : covered) +
                                   ", not the run's DDS domain " + std::to_string(domain));
  }
}

std::vector<std::string> security_arguments(const fs::path& pki_dir, int node_id) {
  if (pki_dir.empty()) return {};
  return {"--security", node_dir(pki_dir, node_id).string()};
}

std::string plugin_directory() {
#ifdef RTHS_DDS_SECURITY_PLUGIN_DIR
  if (fs::is_regular_file(fs::path(RTHS_DDS_SECURITY_PLUGIN_DIR) / "libdds_security_auth.so"))
    return RTHS_DDS_SECURITY_PLUGIN_DIR;
#endif
  return "";
}

std::vector<std::pair<std::string, std::string>> participant_properties(
    const NodeSecurityFiles& files) {
  const std::string dir = plugin_directory();
  const auto library = [&](const std::string& name) {
    return dir.empty() ? name : dir + "/lib" + name + ".so";
  };
  const auto uri = [](const fs::path& file) { return "file:" + fs::absolute(file).string(); };
  return {
      {"dds.sec.auth.library.path", library("dds_security_auth")},
      {"dds.sec.auth.library.init", "init_authentication"},
      {"dds.sec.auth.library.finalize", "finalize_authentication"},
      {"dds.sec.crypto.library.path", library("dds_security_crypto")},
      {"dds.sec.crypto.library.init", "init_crypto"},
      {"dds.sec.crypto.library.finalize", "finalize_crypto"},
      {"dds.sec.access.library.path", library("dds_security_ac")},
      {"dds.sec.access.library.init", "init_access_control"},
      {"dds.sec.access.library.finalize", "finalize_access_control"},
      {"dds.sec.auth.identity_ca", uri(files.identity_ca)},
      {"dds.sec.auth.identity_certificate", uri(files.certificate)},
      {"dds.sec.auth.private_key", uri(files.private_key)},
      {"dds.sec.access.permissions_ca", uri(files.identity_ca)},
      {"dds.sec.access.governance", uri(files.governance)},
      {"dds.sec.access.permissions", uri(files.permissions)},
  };
}

}  // namespace rths::security
