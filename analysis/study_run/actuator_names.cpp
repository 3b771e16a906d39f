#include "analysis/study_run/actuator_names.h"

#include <algorithm>
#include <map>

namespace rths::analysis {
namespace {

// Channels (0-based) in the order the config declares them.
std::vector<int> config_channels(const config::Substructuring& sub, int dofs, int channels) {
  std::vector<int> order;
  if (sub.experimental_dofs_size() > 0) {
    int element = 0;
    for (const config::ExperimentalDof& spec : sub.experimental_dofs()) {
      const bool grounded = spec.influence_size() == 0 && spec.from_dof() == 0;
      order.push_back(grounded ? spec.dof() - 1 : dofs + element++);
    }
    return order;
  }
  if (sub.experimental_storeys_size() > 0) {
    for (int s : sub.experimental_storeys()) order.push_back(s - 1);
    return order;
  }
  for (int s = 0; s < channels; ++s) order.push_back(s);
  return order;
}

// The site of the node hosting channel s, or "".
std::string site_of(const config::Deployment& deployment, int s) {
  for (const config::NodeSpec& node : deployment.nodes()) {
    if (node.site().empty() || node.kind() == config::NodeSpec::SUBSTRUCTURE) continue;
    const auto& hosted = node.storeys();
    if (hosted.empty() || std::find(hosted.begin(), hosted.end(), s + 1) != hosted.end())
      return node.site();
  }
  return "";
}

}  // namespace

std::string ActuatorNames::of(int a) const {
  if (a >= 0 && a < static_cast<int>(names.size())) return names[static_cast<std::size_t>(a)];
  return "actuator " + std::to_string(a + 1);
}

ActuatorNames actuator_names(const config::Study& study, const core::HybridPartition& partition) {
  ActuatorNames out;
  const std::vector<int>& channels = partition.actuator_storeys;
  std::map<std::string, int> per_site;
  std::vector<std::string> sites;
  for (int s : channels) {
    sites.push_back(site_of(study.deployment(), s));
    if (!sites.back().empty()) ++per_site[sites.back()];
  }
  for (std::size_t a = 0; a < channels.size(); ++a) {
    const std::string channel = partition.channel_name(channels[a]);
    if (sites[a].empty())
      out.names.push_back(channel);
    else
      out.names.push_back(per_site[sites[a]] > 1 ? sites[a] + ", " + channel : sites[a]);
  }
  for (int s : config_channels(study.substructuring(), partition.dofs(), partition.channels())) {
    const auto at = std::find(channels.begin(), channels.end(), s);
    if (at != channels.end()) out.order.push_back(static_cast<int>(at - channels.begin()));
  }
  // Any actuator the config's list did not place (none expected) keeps its channel's turn.
  for (std::size_t a = 0; a < channels.size(); ++a)
    if (std::find(out.order.begin(), out.order.end(), static_cast<int>(a)) == out.order.end())
      out.order.push_back(static_cast<int>(a));
  return out;
}

}  // namespace rths::analysis
