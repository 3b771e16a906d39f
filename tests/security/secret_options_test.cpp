// The secret options both programs declare: each lands where the program reads it, and the help
// says whose folder and who could speak without them.
#include "security/secret_options.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <string>
#include <vector>

namespace rths::security {
namespace {

struct Parsed {
  std::string security_dir;
  SecretChoice secret;
};

Parsed parse(std::vector<std::string> args) {
  CLI::App app{"test"};
  Parsed out;
  add_secret_options(app, out.security_dir, out.secret, "the tester's folder",
                     "anyone can speak for the tester");
  std::reverse(args.begin(), args.end());  // CLI11 parses a vector from its back
  app.parse(args);
  return out;
}

TEST(SecretOptions, EachOptionLandsInItsField) {
  const Parsed p = parse({"--security", "pki/node_3", "--secret-file", "run.secret"});
  EXPECT_EQ(p.security_dir, "pki/node_3");
  EXPECT_EQ(p.secret.file, "run.secret");
  EXPECT_FALSE(p.secret.insecure);
  EXPECT_TRUE(parse({"--insecure"}).secret.insecure);
}

TEST(SecretOptions, TheHelpNamesTheFolderTheEnvironmentAndTheRisk) {
  CLI::App app{"test"};
  std::string dir;
  SecretChoice secret;
  add_secret_options(app, dir, secret, "the tester's folder", "anyone can speak for the tester");
  const std::string help = app.help();
  EXPECT_NE(help.find("the tester's folder"), std::string::npos) << help;
  EXPECT_NE(help.find(kSecretFileEnv), std::string::npos) << help;
  EXPECT_NE(help.find("anyone can speak for the tester"), std::string::npos) << help;
}

}  // namespace
}  // namespace rths::security
