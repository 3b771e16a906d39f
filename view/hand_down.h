#pragma once
// What a launcher (`rths sites --view`) hands its coordinator's view, in the coordinator's
// environment (never its command line, which every user of the host can read):
//   RTHS_VIEW_FD     a listening socket (view::open_listener) made in the launcher's network
//                    namespace: the coordinator serves it from inside a site's namespace, so the
//                    page is at the host's address
//   RTHS_VIEW_SITES  the sites as JSON: [{"name": site, "nodes": [ids], "labs_nodes": [ids of its
//                    nodes that drive actuators]}], in the sites config's order; the page groups
//                    nodes and actuators under them, and a lab is a site with such nodes
//   RTHS_VIEW_CREW   the run's role tokens (Crew::to_json): the view then has a control room
// Inputs/outputs: a HandDown; set_hand_down() writes it into this process's environment (for the
// children it starts), handed_down() reads it back (unset variables: none of it).
// Errors: handed_down() throws std::invalid_argument naming the variable that does not parse.

#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "view/control_room.h"

namespace rths::view {

struct SiteLayout {
  std::string name;
  std::vector<int> nodes;      // 0 = the coordinator
  std::vector<int> lab_nodes;  // of `nodes`, those that drive actuators
};

struct HandDown {
  int listen_fd = -1;
  std::vector<SiteLayout> sites;
  std::optional<Crew> crew;
  // Site name -> its nodes that drive actuators, for the sites that have any (ControlDesk's labs).
  std::map<std::string, std::vector<int>> labs() const;
  nlohmann::json sites_json() const;  // as RTHS_VIEW_SITES holds it
};

void set_hand_down(const HandDown& down);
HandDown handed_down();

// The file beside a sites run's record that holds its sites as RTHS_VIEW_SITES does (`rths sites`
// writes it into its output folder; `rths view` of that folder reads it).
inline constexpr const char* kSitesLayoutFile = "sites.json";
// The sites in `file`, as sites_json() writes them. Throws std::invalid_argument naming the file
// when it cannot be read or is not that list.
std::vector<SiteLayout> read_site_layouts(const std::filesystem::path& file);

}  // namespace rths::view
