#include "security/secret_options.h"

namespace rths::security {

void add_secret_options(CLI::App& app, std::string& security_dir, SecretChoice& secret,
                        const std::string& own_folder, const std::string& without_it) {
  app.add_option("--security", security_dir, "DDS Security: " + own_folder);
  app.add_option("--secret-file", secret.file,
                 "the run secret (`rths pki secret FILE`, mode 0600); default: $" +
                     std::string(kSecretFileEnv) + " or $" + kSecretEnv);
  app.add_flag("--insecure", secret.insecure,
               "run without a run secret or DDS Security: " + without_it);
}

}  // namespace rths::security
