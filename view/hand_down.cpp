#include "view/hand_down.h"

#include <cstdlib>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace rths::view {
namespace {

constexpr const char* kFd = "RTHS_VIEW_FD";
constexpr const char* kSites = "RTHS_VIEW_SITES";
constexpr const char* kCrew = "RTHS_VIEW_CREW";

std::optional<std::string> variable(const char* name) {
  const char* value = std::getenv(name);
  if (value == nullptr || *value == '\0') return std::nullopt;
  return std::string(value);
}

nlohmann::json parsed(const char* name, const std::string& text) {
  try {
    return nlohmann::json::parse(text);
  } catch (const nlohmann::json::exception& e) {
    throw std::invalid_argument(std::string(name) + " is not JSON: " + e.what());
  }
}

std::vector<SiteLayout> sites_from(const nlohmann::json& j, const std::string& source) {
  std::vector<SiteLayout> sites;
  try {
    for (const nlohmann::json& site : j)
      sites.push_back({site.at("name").get<std::string>(), site.at("nodes").get<std::vector<int>>(),
                       site.at("lab_nodes").get<std::vector<int>>()});
  } catch (const nlohmann::json::exception& e) {
    throw std::invalid_argument(source + " is not a list of {name, nodes, lab_nodes}: " + e.what());
  }
  return sites;
}

}  // namespace

std::map<std::string, std::vector<int>> HandDown::labs() const {
  std::map<std::string, std::vector<int>> labs;
  for (const SiteLayout& site : sites)
    if (!site.lab_nodes.empty()) labs[site.name] = site.lab_nodes;
  return labs;
}

nlohmann::json HandDown::sites_json() const {
  nlohmann::json j = nlohmann::json::array();
  for (const SiteLayout& site : sites)
    j.push_back({{"name", site.name}, {"nodes", site.nodes}, {"lab_nodes", site.lab_nodes}});
  return j;
}

void set_hand_down(const HandDown& down) {
  if (down.listen_fd >= 0) ::setenv(kFd, std::to_string(down.listen_fd).c_str(), 1);
  if (!down.sites.empty()) ::setenv(kSites, down.sites_json().dump().c_str(), 1);
  if (down.crew) ::setenv(kCrew, down.crew->to_json().dump().c_str(), 1);
}

HandDown handed_down() {
  HandDown down;
  if (const auto fd = variable(kFd)) {
    if (fd->find_first_not_of("0123456789") != std::string::npos || fd->size() > 9)
      throw std::invalid_argument(std::string(kFd) + " '" + *fd + "' is not a file descriptor");
    down.listen_fd = std::stoi(*fd);
  }
  if (const auto sites = variable(kSites)) down.sites = sites_from(parsed(kSites, *sites), kSites);
  if (const auto crew = variable(kCrew)) down.crew = Crew::from_json(parsed(kCrew, *crew));
  return down;
}

std::vector<SiteLayout> read_site_layouts(const std::filesystem::path& file) {
  std::ifstream in(file);
  if (!in) throw std::invalid_argument(file.string() + ": cannot be read");
  std::stringstream text;
  text << in.rdbuf();
  const std::string name = file.string();
  const std::vector<SiteLayout> sites = sites_from(parsed(name.c_str(), text.str()), name);
  if (sites.empty()) throw std::invalid_argument(name + " names no site");
  return sites;
}

}  // namespace rths::view
