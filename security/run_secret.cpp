#include "security/run_secret.h"

#include <fcntl.h>
#include <openssl/rand.h>
#include <sys/stat.h>
#include <unistd.h>

#include <array>
#include <bitset>
#include <cerrno>
#include <cstdlib>
#include <cstring>
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

// Why `text` cannot be a run secret, or empty when it can. One case only: MessageMac keys on the
// text, so "AB.." and "ab.." would be two keys and the processes given each would drop the
// other's messages as forged; generate_run_secret writes lower case, so upper case is refused
// (never silently folded: a secret typed by hand is what the entropy checks below are for).
// A random secret uses about 16 different digits and never repeats a pattern of 32 or fewer
// (either happens by chance with odds under 1e-18); one that does was typed, not drawn.
std::string secret_flaw(const std::string& text) {
  if (text.size() != kSecretHexChars ||
      text.find_first_not_of("0123456789abcdefABCDEF") != std::string::npos)
    return "does not hold one secret of 64 hex characters (`rths pki secret FILE` makes one)";
  if (text.find_first_of("ABCDEF") != std::string::npos)
    return "is in upper case: a run secret is written in lower case, as `rths pki secret` writes "
           "it (the messages' MAC keys on the text, so an upper-case copy is another key); "
           "lower-case it everywhere it is given";
  std::bitset<128> seen;
  for (const char c : text) seen.set(static_cast<unsigned char>(c));
  if (seen.count() < 8)
    return "uses " + std::to_string(seen.count()) +
           " different hex digits (a random secret uses about 16): not a random secret; make one "
           "with `rths pki secret FILE`";
  for (std::size_t period = 1; period <= kSecretHexChars / 2; ++period)
    if (text.compare(period, std::string::npos, text, 0, text.size() - period) == 0)
      return "repeats its first " + std::to_string(period) +
             " digits over and over: a pattern, not a random secret; make one with `rths pki "
             "secret FILE`";
  return "";
}

// What a file that is not a regular file is, in words.
std::string file_kind(mode_t mode) {
  if (S_ISFIFO(mode)) return "named pipe";
  if (S_ISDIR(mode)) return "directory";
  if (S_ISCHR(mode)) return "character device";
  if (S_ISBLK(mode)) return "block device";
  if (S_ISSOCK(mode)) return "socket";
  return "special file";
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

namespace {

// The file's metadata, refused unless a regular file that only its owner may read or write: a
// named pipe would block the open or the read (start-up hangs), a device never ends.
struct stat secret_file_status(const std::filesystem::path& file) {
  struct stat st {};
  if (::stat(file.c_str(), &st) != 0) throw SecretError(errno_text(file, "cannot read"));
  if (!S_ISREG(st.st_mode))
    throw SecretError(secret_file_error(
        file, "is a " + file_kind(st.st_mode) +
                  ", not a regular file; give the file `rths pki secret FILE` wrote"));
  if ((st.st_mode & (S_IRWXG | S_IRWXO)) != 0) {
    std::ostringstream mode;
    mode << std::oct << (st.st_mode & 0777);
    throw SecretError(secret_file_error(
        file, "mode " + mode.str() + " lets others read it; chmod 600 it (or make a new one)"));
  }
  return st;
}

// The file's first bytes, at most `limit`, read without blocking from the file checked above
// (a file swapped for another kind between the check and the open is refused).
std::string read_head(const std::filesystem::path& file, const struct stat& checked,
                      std::size_t limit) {
  const int fd = ::open(file.c_str(), O_RDONLY | O_NONBLOCK | O_NOCTTY | O_CLOEXEC);
  if (fd < 0) throw SecretError(errno_text(file, "cannot read"));
  struct stat opened {};
  std::string head(limit, '\0');
  std::size_t got = 0;
  ssize_t n = 0;
  const bool same = ::fstat(fd, &opened) == 0 && S_ISREG(opened.st_mode) &&
                    opened.st_dev == checked.st_dev && opened.st_ino == checked.st_ino;
  while (same && got < limit && (n = ::read(fd, &head[got], limit - got)) > 0)
    got += static_cast<std::size_t>(n);
  const int saved = errno;
  ::close(fd);
  errno = saved;
  if (!same) throw SecretError(secret_file_error(file, "changed while it was opened"));
  if (n < 0) throw SecretError(errno_text(file, "cannot read"));
  head.resize(got);
  return head;
}

}  // namespace

std::string read_run_secret_file(const std::filesystem::path& file) {
  const struct stat st = secret_file_status(file);
  // One secret and its newline; a byte more is refused below, so no more is read.
  std::string secret = read_head(file, st, kSecretHexChars + 2);
  if (!secret.empty() && secret.back() == '\n') secret.pop_back();
  if (const std::string why = secret_flaw(secret); !why.empty())
    throw SecretError(secret_file_error(file, why));
  return secret;
}

std::string resolve_run_secret(const SecretChoice& choice) {
  if (!choice.file.empty()) return read_run_secret_file(choice.file);
  if (const char* file = std::getenv(kSecretFileEnv); file && *file)
    return read_run_secret_file(file);
  if (const char* value = std::getenv(kSecretEnv); value && *value) {
    const std::string secret = value;
    ::unsetenv(kSecretEnv);
    if (const std::string why = secret_flaw(secret); !why.empty())
      throw SecretError(std::string(kSecretEnv) + " " + why);
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
