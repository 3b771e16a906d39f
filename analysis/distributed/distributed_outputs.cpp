#include "analysis/distributed/distributed_outputs.h"

#include <algorithm>
#include <vector>

#include "analysis/study_run/response_envelope_plots.h"
#include "analysis/tables/result_tables.h"
#include "core/time_text.h"
#include "results/results.h"
#include "results/write.h"
#include "util/atomic_file.h"
#include "util/plot.h"

namespace rths::analysis {
namespace {

std::vector<double> in_ms(const std::vector<double>& seconds, double offset = 0.0) {
  std::vector<double> out;
  out.reserve(seconds.size());
  for (double x : seconds) out.push_back((x + offset) * 1e3);
  return out;
}

std::vector<std::string> lag_plot_files(const DistributedResults& results) {
  std::vector<std::string> files;
  for (const auto& c : results.outcome.cases)
    for (const char* extension : {".png", ".svg"}) files.push_back("links_" + c.name + extension);
  return files;
}

}  // namespace

std::filesystem::path write_distributed_outputs(
    const DistributedResults& results, const std::filesystem::path& out, bool plots,
    const std::string& format, const std::function<void(const std::string&)>& warn) {
  std::filesystem::create_directories(out);
  const results::Format kind = results::parse_format(format);
  const std::filesystem::path table_file = out / ("results" + results::extension(kind));
  if (!results.outcome.cases.empty())
    results::write_table(analysis::distributed_study_table(results.outcome, results.links),
                         table_file, kind);
  if (!plots) {
    // A folder must not show plots of an earlier run beside this run's results.
    for (const std::string& file : analysis::study_plot_files(out))
      std::filesystem::remove(out / file);
    for (const std::string& file : lag_plot_files(results)) std::filesystem::remove(out / file);
  } else if (!results.outcome.cases.empty()) {
    try {
      analysis::write_study_plots(results.outcome, out);
      for (std::size_t i = 0; i < results.outcome.cases.size(); ++i)
        if (!results.links[i].empty())
          write_lag_plot(results, i, out / ("links_" + results.outcome.cases[i].name + ".png"));
    } catch (const std::exception& e) {
      warn(std::string("plots not written: ") + e.what());
    }
  }
  util::AtomicFile json_file(out / "summary.json");
  json_file.stream() << distributed_summary_json(results).dump(2) << "\n";
  json_file.commit();
  util::AtomicFile text_file(out / "summary.txt");
  text_file.stream() << distributed_summary_text(results);
  text_file.commit();
  return table_file;
}

namespace {

std::string link_label(const DistributedCaseFacts& facts, int node) {
  const auto it = facts.link_labels.find(node);
  return it != facts.link_labels.end() ? it->second : "node " + std::to_string(node);
}

// Each link's injected and measured round trip; actuator_link_colour is the colour of the
// actuator's link's measured curve, which the stack panel repeats.
util::PlotSpec network_panel(const analysis::CaseOutcome& c, const DistributedCaseFacts& facts,
                             const std::map<int, runtime::LinkSeries>& links,
                             const ActuatorPathLag& path, std::string& actuator_link_colour) {
  util::PlotSpec network;
  network.title = "network lag per link, case " + c.name + " (" +
                  (path.real_time ? "real time" : "lockstep") + ")";
  network.xlabel = "time (s)";
  network.ylabel = "round trip (ms)";
  for (const auto& [node, series] : links) {
    // Injected first, so the measured round trip is drawn over it.
    // Thick and dashed: in lockstep it lies on zero, under the processes' own exchange times.
    network.series.push_back({link_label(facts, node) + ": round trip, injected", series.time,
                              in_ms(series.injected), "lines lw 3 dt 2"});
    if (node == path.node_id) actuator_link_colour = util::series_colour(network.series.size());
    network.series.push_back({link_label(facts, node) + ": round trip, measured", series.time,
                              in_ms(series.round_trip)});
  }
  if (!path.real_time)
    network.title = "wall-clock round trip per link, case " + c.name +
                    " (lockstep: simulated time carries no network lag; these are the processes' "
                    "own exchange times)";
  return network;
}

// The stack: the network round trip the test feels (real time only), the actuator's own lag
// on top of it; drawn as the total filled first, then the network part over its lower band.
// Colours continue from the network panel's, at colour.
util::PlotSpec stack_panel(const analysis::CaseOutcome& c, const DistributedCaseFacts& facts,
                           const std::map<int, runtime::LinkSeries>& links,
                           const ActuatorPathLag& path, const std::string& actuator_link_colour,
                           std::size_t colour) {
  const double t0 = c.simulation.time.empty() ? 0.0 : c.simulation.time.front();
  const double t1 = c.simulation.time.empty() ? 0.0 : c.simulation.time.back();
  const double actuator = c.nominal_delay + path.node_stages;  // s
  const std::string actuator_label = "actuator lag, nominal " + core::format_ms(actuator) + ": " +
                                     c.delay_description +
                                     (path.node_stages != 0.0 ? " + node stages" : "");
  util::PlotSpec stack;
  stack.title =
      path.real_time
          ? "lag the test feels on the actuator's path: network round trip + actuator lag (stacked)"
          : "lag the test feels on the actuator's path: actuator lag (lockstep: the network does "
            "not enter)";
  stack.xlabel = "time (s)";
  stack.ylabel = "lag (ms)";
  const std::string fill = " fs solid 0.45 noborder";  // opaque: the lower band covers the upper's
  const auto link = links.find(path.node_id);
  if (path.real_time && link != links.end()) {
    const runtime::LinkSeries& s = link->second;
    stack.series.push_back(
        {actuator_label, s.time, in_ms(s.round_trip, actuator),
         "filledcurves y1=0 lc rgb '" + util::series_colour(colour++) + "' dt 1" + fill});
    stack.series.push_back({link_label(facts, path.node_id) + ": network round trip, measured",
                            s.time, in_ms(s.round_trip),
                            "filledcurves y1=0 lc rgb '" + actuator_link_colour + "' dt 1" + fill});
    stack.series.push_back({"injected total: network + actuator", s.time,
                            in_ms(s.injected, actuator),
                            "lines lw 1.5 lc rgb '" + util::series_colour(colour++) + "'"});
  } else {
    stack.series.push_back(
        {actuator_label,
         {t0, t1},
         {actuator * 1e3, actuator * 1e3},
         "filledcurves y1=0 lc rgb '" + util::series_colour(colour++) + "' dt 1" + fill});
  }
  if (c.stability) {
    const auto level = [&](const std::optional<double>& limit, const std::string& what,
                           const char* dash) {
      if (!limit) return;
      stack.series.push_back({what + " critical delay " + core::format_ms(*limit),
                              {t0, t1},
                              {*limit * 1e3, *limit * 1e3},
                              std::string("lines lw 2 dt ") + dash + " lc rgb '" +
                                  util::series_colour(colour++) + "'"});
    };
    level(c.stability->continuous, "continuous", "2");
    level(c.stability->discrete, "discrete", "3");
  }
  return stack;
}

}  // namespace

void write_lag_plot(const DistributedResults& results, std::size_t case_index,
                    const std::filesystem::path& png) {
  const analysis::CaseOutcome& c = results.outcome.cases.at(case_index);
  const DistributedCaseFacts& facts = results.facts.at(case_index);
  const std::map<int, runtime::LinkSeries>& links = results.links.at(case_index);
  const ActuatorPathLag& path = results.actuator_path;
  std::string actuator_link_colour = util::series_colour(0);
  util::PlotSpec network = network_panel(c, facts, links, path, actuator_link_colour);
  util::PlotSpec stack =
      stack_panel(c, facts, links, path, actuator_link_colour, network.series.size());
  // From zero, and high enough that the critical delays are never on the border; the network
  // panel a little below zero, so that an injected lag of zero is seen, not hidden in the axis.
  stack.y_min = 0.0;
  if (const auto range = util::padded_y_range(network.series, {}))
    network.y_min = -0.05 * std::max(range->second, 1e-3);
  if (const auto range = util::padded_y_range(stack.series, {})) stack.y_max = range->second;
  network.height = stack.height = 380;
  std::vector<util::PlotSpec> panels;
  if (!network.series.empty()) panels.push_back(network);
  panels.push_back(stack);
  util::write_png_panels(panels, png);
}

}  // namespace rths::analysis
