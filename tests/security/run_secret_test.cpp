// The run secret (security/run_secret.h): made random, kept in a file only its owner reads, and
// refused in every other form; a program without one refuses unless security or --insecure.
#include "security/run_secret.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <cctype>
#include <cstdlib>
#include <fstream>
#include <set>

#include "support.h"

namespace rths::security {
namespace {

using testing::HasSubstr;

// Clears both variables for the test, and restores nothing: no test here relies on them.
void clear_environment() {
  ::unsetenv(kSecretEnv);
  ::unsetenv(kSecretFileEnv);
}

std::string message_of(const SecretChoice& choice) {
  try {
    resolve_run_secret(choice);
  } catch (const SecretError& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(RunSecret, EachSecretIs64HexCharactersAndNoTwoAreAlike) {
  std::set<std::string> seen;
  for (int i = 0; i < 100; ++i) {
    const std::string secret = generate_run_secret();
    ASSERT_EQ(secret.size(), kSecretHexChars);
    EXPECT_EQ(secret.find_first_not_of("0123456789abcdef"), std::string::npos) << secret;
    seen.insert(secret);
  }
  EXPECT_EQ(seen.size(), 100u);
}

TEST(RunSecret, AFileIsWrittenForItsOwnerAloneAndReadBack) {
  const auto dir = test::fresh_dir("secret_file");
  std::filesystem::create_directories(dir);
  const auto file = dir / "run.secret";
  const std::string secret = generate_run_secret();
  write_run_secret_file(file, secret);
  struct stat st {};
  ASSERT_EQ(::stat(file.c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 0777, 0600u);
  EXPECT_EQ(read_run_secret_file(file), secret);
  EXPECT_THROW(write_run_secret_file(file, secret), std::runtime_error) << "never overwritten";
}

TEST(RunSecret, AFileOthersMayReadOrThatHoldsNoSecretIsRefusedByName) {
  const auto dir = test::fresh_dir("secret_refused");
  std::filesystem::create_directories(dir);
  const auto open_file = dir / "open.secret";
  write_run_secret_file(open_file, generate_run_secret());
  ::chmod(open_file.c_str(), 0644);
  EXPECT_THAT(message_of({open_file, false, false}),
              testing::AllOf(HasSubstr(open_file.string()), HasSubstr("mode 644")));
  const auto short_file = dir / "short.secret";
  write_run_secret_file(short_file, "abc123");
  EXPECT_THAT(message_of({short_file, false, false}), HasSubstr("64 hex characters"));
  const auto two_lines = dir / "two.secret";
  write_run_secret_file(two_lines, generate_run_secret() + "\n" + generate_run_secret());
  EXPECT_THAT(message_of({two_lines, false, false}), HasSubstr("64 hex characters"));
  EXPECT_THAT(message_of({dir / "missing", false, false}), HasSubstr("cannot read"));
}

TEST(RunSecret, ANamedPipeOrADirectoryIsRefusedByItsTypeWithoutBeingOpened) {
  const auto dir = test::fresh_dir("secret_kind");
  std::filesystem::create_directories(dir);
  const auto pipe = dir / "run.secret";
  ASSERT_EQ(::mkfifo(pipe.c_str(), 0600), 0);
  // Opened for reading, a pipe with no writer blocks: this returns only if it never is.
  EXPECT_THAT(message_of({pipe, false, false}),
              testing::AllOf(HasSubstr(pipe.string()), HasSubstr("named pipe"),
                             HasSubstr("not a regular file")));
  const auto folder = dir / "folder";
  std::filesystem::create_directories(folder);
  ::chmod(folder.c_str(), 0700);
  EXPECT_THAT(message_of({folder, false, false}),
              testing::AllOf(HasSubstr(folder.string()), HasSubstr("directory")));
}

// The secret `text` written to a fresh 0600 file, and what reading it says.
std::string file_verdict(const std::string& name, const std::string& text) {
  const auto dir = test::fresh_dir("secret_form_" + name);
  std::filesystem::create_directories(dir);
  write_run_secret_file(dir / "run.secret", text);
  return message_of({dir / "run.secret", false, false});
}

TEST(RunSecret, UpperCaseAndLowEntropySecretsAreRefusedFromAFileAndFromTheEnvironment) {
  const std::string drawn = generate_run_secret();
  std::string upper = drawn, mixed = drawn, seven = drawn;
  for (char& c : upper) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  mixed[drawn.find_first_of("abcdef")] = upper[drawn.find_first_of("abcdef")];
  for (char& c : seven) c = static_cast<char>('0' + (c % 7));  // 0-6 only, no period
  EXPECT_THAT(file_verdict("upper", upper), HasSubstr("upper case"));
  EXPECT_THAT(file_verdict("mixed", mixed), HasSubstr("upper case"));
  EXPECT_THAT(file_verdict("zero", std::string(64, '0')), HasSubstr("uses 1 different hex digits"));
  EXPECT_THAT(file_verdict("seven", seven), HasSubstr("different hex digits"));
  std::string beef, eight, counting;
  for (int i = 0; i < 8; ++i) beef += "deadbeef";
  for (int i = 0; i < 8; ++i) eight += "a1b2c3d4";
  for (int i = 0; i < 4; ++i) counting += "0123456789abcdef";
  EXPECT_THAT(file_verdict("beef", beef), HasSubstr("uses 5 different hex digits"));
  EXPECT_THAT(file_verdict("eight", eight), HasSubstr("repeats its first 8 digits"));
  EXPECT_THAT(file_verdict("counting", counting), HasSubstr("repeats its first 16 digits"));
  EXPECT_THAT(file_verdict("half", drawn.substr(0, 32) + drawn.substr(0, 32)),
              HasSubstr("repeats its first 32 digits"));
  EXPECT_EQ(file_verdict("drawn", drawn), "(no error)");
  clear_environment();
  ::setenv(kSecretEnv, upper.c_str(), 1);
  EXPECT_THAT(message_of({}), testing::AllOf(HasSubstr(kSecretEnv), HasSubstr("upper case")));
  ::setenv(kSecretEnv, std::string(64, '0').c_str(), 1);
  EXPECT_THAT(message_of({}), testing::AllOf(HasSubstr(kSecretEnv), HasSubstr("uses 1")));
  clear_environment();
}

TEST(RunSecret, TheEnvironmentGivesItOnceAndTheFileOptionComesFirst) {
  clear_environment();
  const auto dir = test::fresh_dir("secret_env");
  std::filesystem::create_directories(dir);
  const auto file = dir / "run.secret";
  const std::string from_file = generate_run_secret();
  write_run_secret_file(file, from_file);
  const std::string from_env = generate_run_secret();
  ::setenv(kSecretEnv, from_env.c_str(), 1);
  EXPECT_EQ(resolve_run_secret({file, false, false}), from_file);
  EXPECT_EQ(resolve_run_secret({}), from_env);
  EXPECT_EQ(std::getenv(kSecretEnv), nullptr) << "read once, then gone from the environment";
  ::setenv(kSecretFileEnv, file.c_str(), 1);
  EXPECT_EQ(resolve_run_secret({}), from_file);
  clear_environment();
  ::setenv(kSecretEnv, "not-a-secret", 1);
  EXPECT_THAT(message_of({}), HasSubstr(kSecretEnv));
  clear_environment();
}

TEST(RunSecret, NoneIsRefusedUnlessSecurityOrInsecureSaysSo) {
  clear_environment();
  const std::string why = message_of({});
  EXPECT_THAT(why, testing::AllOf(HasSubstr("no run secret"), HasSubstr("rths launch"),
                                  HasSubstr("rths pki secret FILE"), HasSubstr("--insecure")));
  EXPECT_EQ(resolve_run_secret({{}, true, false}), "");
  EXPECT_EQ(resolve_run_secret({{}, false, true}), "");
}

}  // namespace
}  // namespace rths::security
