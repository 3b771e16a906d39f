#pragma once
// Loading a config of the expected kind, and naming the kind a mismatched file is (a study, a
// joint-lag study, a sites file), so that `rths run sites.textproto` says which command to use.
#include <filesystem>
#include <functional>
#include <stdexcept>
#include <string>

namespace rths::cli {

// Which kind of config a text-format file parses as: "study (rths.config.Study)", "joint-lag
// study (rths.analysis.JointLagStudy)", "sites (rths.deploy.Sites)", or empty when none.
std::string config_kind_of(const std::filesystem::path& path);

// Calls `load`; when it throws std::invalid_argument and the file parses as another kind of
// config, rethrows with "FILE is a <kind> config, not a <expected> config (use `rths <command>`)".
template <class Config>
Config load_config_as(const std::filesystem::path& path, const std::string& expected_kind,
                      const std::function<Config(const std::filesystem::path&)>& load);
void rethrow_with_config_kind(const std::filesystem::path& path, const std::string& expected_kind,
                              const std::invalid_argument& error);

template <class Config>
Config load_config_as(const std::filesystem::path& path, const std::string& expected_kind,
                      const std::function<Config(const std::filesystem::path&)>& load) {
  try {
    return load(path);
  } catch (const std::invalid_argument& e) {
    rethrow_with_config_kind(path, expected_kind, e);
    throw;
  }
}

}  // namespace rths::cli
