#pragma once
// The command-line options every DDS participant's program takes for its run secret and DDS
// Security, declared once so that the coordinator and the nodes read them the same way:
//   --security DIR     this participant's folder from `rths pki init` (`own_folder` says which,
//                      where it comes from and its default)
//   --secret-file F    the run secret (`rths pki secret FILE`, mode 0600); default: the
//                      environment's (kSecretFileEnv, else kSecretEnv)
//   --insecure         neither; `without_it` says who could then speak for whom
// The values land in `security_dir` and `secret`; resolve_run_secret (run_secret.h) turns them into the secret.

#include <CLI/CLI.hpp>
#include <string>

#include "security/run_secret.h"

namespace rths::security {

void add_secret_options(CLI::App& app, std::string& security_dir, SecretChoice& secret,
                        const std::string& own_folder, const std::string& without_it);

}  // namespace rths::security
