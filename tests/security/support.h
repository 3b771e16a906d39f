#pragma once
// Shared by the security tests: a lab PKI made once per test in a fresh directory, and the
// openssl command line to make documents the way a lab might by hand.

#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include "security/pki.h"
#include "study/text_format.h"

namespace rths::test {

inline std::filesystem::path fresh_dir(const std::string& name) {
  const auto dir = std::filesystem::temp_directory_path() /
                   ("rths_security_" + name + "_" + std::to_string(getpid()));
  std::filesystem::remove_all(dir);
  return dir;
}

// Coordinator (0), a substructure node (1) and an actuator emulator (2).
inline std::filesystem::path make_lab(const std::string& name,
                                      const std::string& organisation = "rths-lab") {
  const auto dir = fresh_dir(name);
  security::PkiOptions options;
  options.organisation = organisation;
  options.nodes = {{1, "substructure"}, {2, "actuator_emulator"}};
  security::init_pki(dir, options);
  return dir;
}

inline std::string slurp(const std::filesystem::path& path) {
  return study::read_text_file(path, "test output");
}

// Signs `xml` with the lab CA in `pki` into `out` with the openssl command line (S/MIME, text).
inline void sign_with_openssl(const std::filesystem::path& pki, const std::string& xml,
                              const std::filesystem::path& out) {
  const auto input = out.string() + ".in.xml";
  std::ofstream(input) << xml;
  const std::string command = "openssl smime -sign -text -in '" + input + "' -signer '" +
                              (pki / "ca" / "ca_cert.pem").string() + "' -inkey '" +
                              (pki / "ca" / "ca_key.pem").string() + "' -out '" + out.string() +
                              "'";
  if (std::system(command.c_str()) != 0) throw std::runtime_error("failed: " + command);
  std::filesystem::remove(input);
}

}  // namespace rths::test
