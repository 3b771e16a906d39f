#include "study/case_link.h"

#include <algorithm>
#include <stdexcept>

namespace rths::study {

core::LinkWay link_way(const config::LinkLag& lag) {
  core::LinkWay way;
  way.one_way_delay = lag.one_way_delay();
  way.jitter = lag.jitter();
  way.seed = lag.seed();
  way.loss = lag.loss();
  const config::NetworkEmulation& net = lag.network();
  way.drift_rate = net.drift_rate();
  way.spike_delay = net.spike_delay();
  way.spike_every = net.spike_every();
  way.spike_steps = net.spike_steps();
  way.drop_first_step = net.drop_first_step();
  way.drop_steps = net.drop_steps();
  return way;
}

void apply_case_links(core::HybridSetup& setup,
                      const google::protobuf::RepeatedPtrField<config::CaseLink>& links,
                      const std::string& where) {
  setup.links.clear();
  if (links.empty()) return;
  const auto actuators = static_cast<int>(setup.partition.actuator_storeys.size());
  if (links.size() != 1 && links.size() != actuators)
    throw std::invalid_argument(where + ": " + std::to_string(links.size()) + " link blocks for " +
                                std::to_string(actuators) +
                                " actuators: give one for every actuator or one per actuator");
  for (int a = 0; a < actuators; ++a) {
    const config::CaseLink& link = links.size() == 1 ? links.Get(0) : links.Get(a);
    setup.links.push_back({link_way(link.to_node()), link_way(link.from_node())});
  }
}

double answer_lag(const core::HybridSetup& setup) {
  double lag = 0.0;
  for (std::size_t a = 0; a < setup.delays.size(); ++a)
    lag = std::max(lag,
                   setup.delays[a].nominal_delay() +
                       (a < setup.links.size() ? core::nominal_round_trip(setup.links[a]) : 0.0));
  return lag;
}

std::string case_delay_text(const core::HybridSetup& setup) {
  if (setup.delays.empty()) return "no experimental substructure";
  std::string text = setup.delays.front().describe();
  if (!setup.links.empty()) text += "; " + core::describe_link(setup.links.front());
  return text;
}

}  // namespace rths::study
