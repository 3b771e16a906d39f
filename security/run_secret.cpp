#include "security/run_secret.h"

#include <fcntl.h>
#include <openssl/rand.h>
#include <sys/stat.h>
#include <unistd.h>

#include <array>
#include <cctype>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>

namespace rths::security {

namespace {

std::string errno_text(const std::filesystem::path& file, const char* what) {
  std::string text = what;
  text += " ";
  text += file.string();
  text += ": ";
  text += std::strerror(errno);
  return text;
}

bool is_hex_secret(const std::string& text) {
  if (text.size() != kSecretHexChars) return false;
  for (const char c : text)
    if (!std::isxdigit(static_cast<unsigned char>(c))) return false;
  return true;
}

std::string secret_file_error(const std::filesystem::path& file, const std::string& why) {
  std::string text = "run secret file ";
  text += file.string();
  text += ": ";
  text += why;
  return text;
}

}  // namespace

std::string generate_run_secret() {
  std::array<unsigned char, kSecretHexChars / 2> bytes{};
  if (RAND_bytes(bytes.data(), static_cast<int>(bytes.size())) != 1)
    throw std::runtime_error("OpenSSL RAND_bytes could not make a run secret");
  static const char* const kHex = "0123456789abcdef";
  std::string secret;
  for (const unsigned char b : bytes) {
    secret += kHex[b >> 4];
    secret += kHex[b & 15];
  }
  return secret;
}

void write_run_secret_file(const std::filesystem::path& file, const std::string& secret) {
  const int fd = ::open(file.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0600);
  if (fd < 0) throw std::runtime_error(errno_text(file, "cannot create"));
  const std::string line = secret + "\n";
  const ssize_t written = ::write(fd, line.data(), line.size());
  const int saved = errno;
  ::close(fd);
  errno = saved;
  if (written != static_cast<ssize_t>(line.size()))
    throw std::runtime_error(errno_text(file, "cannot write"));
}

std::string read_run_secret_file(const std::filesystem::path& file) {
  struct stat st {};
  if (::stat(file.c_str(), &st) != 0) throw SecretError(errno_text(file, "cannot read"));
  if ((st.st_mode & (S_IRWXG | S_IRWXO)) != 0) {
    std::ostringstream mode;
    mode << std::oct << (st.st_mode & 0777);
    std::string why = "mode ";
    why += mode.str();
    why += " lets others read it; chmod 600 it (or make a new one)";
    throw SecretError(secret_file_error(file, why));
  }
  std::ifstream in(file);
  std::string secret, rest;
  std::getline(in, secret);
  std::getline(in, rest, '\0');
  if (!is_hex_secret(secret) || !rest.empty())
    throw SecretError(secret_file_error(
        file, "does not hold one secret of 64 hex characters (`rths pki secret FILE` makes one)"));
  return secret;
}

std::string resolve_run_secret(const SecretChoice& choice) {
  if (!choice.file.empty()) return read_run_secret_file(choice.file);
  if (const char* file = std::getenv(kSecretFileEnv); file && *file)
    return read_run_secret_file(file);
  if (const char* value = std::getenv(kSecretEnv); value && *value) {
    const std::string secret = value;
    ::unsetenv(kSecretEnv);
    if (!is_hex_secret(secret))
      throw SecretError(std::string(kSecretEnv) + " does not hold a secret of 64 hex characters");
    return secret;
  }
  if (choice.dds_security || choice.insecure) return {};
  throw SecretError(
      "no run secret: without one (or DDS Security) any participant on the domain can speak as "
      "a node before the coordinator knows it. Run under `rths launch` (it makes one), or make "
      "one with `rths pki secret FILE` and give every process --secret-file FILE (or " +
      std::string(kSecretFileEnv) +
      "=FILE), or use DDS Security (--security); --insecure runs without, accepting that");
}

}  // namespace rths::security
