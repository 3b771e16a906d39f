#pragma once
// The run secret: the identity of a run's processes when DDS Security is off. Every message of
// the run carries a MAC under it (transport/message_mac.h), so a participant that joins the
// domain without it cannot speak as a node or as the coordinator, not even before a node's
// writer is pinned.
//
// A secret is 32 random bytes (OpenSSL RAND_bytes) written as 64 hex characters. It is never
// published: `rths launch` makes one per run and hands it to the processes it starts in their
// environment (kSecretEnv; the environment of a process is readable only by its user, unlike its
// command line); an operator starting processes by hand writes one to a file that only its owner
// may read (`rths pki secret FILE`) and gives each process that file (--secret-file, or the
// kSecretFileEnv variable).
//
// Without a secret a process talks to anyone on its domain. That is refused unless DDS Security
// is on (identity from the certificates) or the operator says --insecure.
//
// Nothing here runs on a loop thread; every function may allocate and read files.

#include <filesystem>
#include <stdexcept>
#include <string>

namespace rths::security {

inline constexpr const char* kSecretEnv = "RTHS_RUN_SECRET";           // the secret itself
inline constexpr const char* kSecretFileEnv = "RTHS_RUN_SECRET_FILE";  // a file holding it
inline constexpr std::size_t kSecretHexChars = 64;

// 64 hex characters from RAND_bytes. Throws std::runtime_error when OpenSSL has no entropy.
std::string generate_run_secret();

// Writes `secret` to `file`, created with mode 0600 (a file that exists already is refused: it
// may be readable by others). Throws std::runtime_error naming the file and errno's reason.
void write_run_secret_file(const std::filesystem::path& file, const std::string& secret);

// The secret in `file`, refused (SecretError naming the file and why) when the file is missing,
// not a regular file (a named pipe, a device, a directory: named by its type, and never opened,
// so start-up cannot block on it), readable or writable by its group or by others, or does not
// hold exactly one well-formed secret (a trailing newline allowed). At most kSecretHexChars + 2
// bytes are read.
// Well-formed, here and for kSecretEnv: kSecretHexChars hex digits in lower case (upper case is
// refused, not folded: the messages' MAC keys on the text, so it would be another key), using at
// least 8 different digits and repeating no pattern of 32 digits or fewer (an all-zero secret, or
// "deadbeef" eight times, is refused; a random one is, with odds under 1e-18).
std::string read_run_secret_file(const std::filesystem::path& file);

struct SecretError : std::invalid_argument {
  using std::invalid_argument::invalid_argument;
};

// What a program was told about its secret.
struct SecretChoice {
  std::filesystem::path file;  // --secret-file; empty: the environment's
  bool insecure = false;       // --insecure
  bool dds_security = false;   // DDS Security is on for this participant
};

// The secret this process uses: --secret-file, else kSecretFileEnv, else kSecretEnv (removed
// from the environment once read, so no child inherits it by accident). Empty when there is none
// and the choice allows that (DDS Security or insecure). Throws SecretError naming every way to
// give one, and why running without one is refused.
std::string resolve_run_secret(const SecretChoice& choice);

}  // namespace rths::security
