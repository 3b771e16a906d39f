#include "identify/run/run_report.h"

#include <algorithm>

#include "util/plot.h"

namespace rths::identify {
namespace {

std::vector<double> scaled(const std::vector<double>& x, double factor) {
  std::vector<double> out(x.size());
  std::transform(x.begin(), x.end(), out.begin(), [&](double v) { return v * factor; });
  return out;
}

std::vector<double> column(const core::Mat& m, Eigen::Index col, double factor) {
  std::vector<double> out(static_cast<std::size_t>(m.rows()));
  for (Eigen::Index k = 0; k < m.rows(); ++k) out[static_cast<std::size_t>(k)] = factor * m(k, col);
  return out;
}

std::string effects_of(const NetworkPath& l) {
  std::string out;
  for (const auto& e : l.effects) out += (out.empty() ? "" : ", ") + e.name;
  return out.empty() ? "no undeclared effect" : out;
}

std::filesystem::path lag_plot(const RunIdentification& run, const std::filesystem::path& dir) {
  std::vector<util::PlotSpec> panels;
  for (const auto& l : run.links) {
    util::PlotSpec p("link to node " + std::to_string(l.node_id) + ": round trip over the run (" +
                         effects_of(l) + ")",
                     "time (s)", "lag (ms)");
    // Where all three agree none hides another: the injected lag a wide pale band under the
    // measured points, the model a dashed line over them.
    p.series.emplace_back("injected by the node", l.time, scaled(l.injected, 1e3),
                          "lines lw 6 lc rgb '#BBBBBB'");
    p.series.emplace_back("measured round trip", l.time, scaled(l.round_trip, 1e3),
                          "points pt 7 ps 0.3 lc rgb '" + util::series_colour(0) + "'");
    p.series.emplace_back("identified model", l.time, scaled(l.model, 1e3),
                          "lines lw 2 dt 2 lc rgb '" + util::series_colour(1) + "'");
    p.height = 400;
    panels.push_back(std::move(p));
  }
  const auto png = dir / "record_lag.png";
  util::write_png_panels(panels, png);
  return png;
}

std::filesystem::path response_plot(const RunResidual& r, const std::filesystem::path& dir) {
  std::vector<util::PlotSpec> panels;
  for (std::size_t c = 0; c < r.floors.size(); ++c) {
    const FloorError& f = r.floors[c];
    const auto i = static_cast<Eigen::Index>(c);  // the responses' column of f.dof
    const auto recorded = column(r.recorded_response, i, 1e3);
    const auto declared = column(r.declared_response, i, 1e3);
    const auto identified = column(r.identified_response, i, 1e3);
    util::PlotSpec p(
        "floor " + std::to_string(f.dof) + ": displacement, recorded and re-run in process",
        "time (s)", "displacement (mm)");
    p.series.emplace_back("recorded", r.time, recorded, "lines lw 3");
    p.series.emplace_back("declared model (NRMSE " + percent_text(f.declared) + ")", r.time,
                          declared);
    p.series.emplace_back("identified model (NRMSE " + percent_text(f.identified) + ")", r.time,
                          identified, "lines dt 2 lw 2");
    // The recorded and identified responses set the range: a diverged declared re-run is clipped.
    if (const auto range = util::padded_y_range(p.series, {0, 2}, 0.15)) {
      p.y_min = range->first;
      p.y_max = range->second;
    }
    util::PlotSpec e("floor " + std::to_string(f.dof) + ": error against the record", "time (s)",
                     "error (mm)");
    std::vector<double> de(recorded.size()), ie(recorded.size());
    for (std::size_t k = 0; k < recorded.size(); ++k) {
      de[k] = declared[k] - recorded[k];
      ie[k] = identified[k] - recorded[k];
    }
    // The colours of the re-runs they come from in the panel above.
    e.series.emplace_back("declared - recorded", r.time, de,
                          "lines lc rgb '" + util::series_colour(1) + "'");
    e.series.emplace_back("identified - recorded", r.time, ie,
                          "lines lw 2 dt 2 lc rgb '" + util::series_colour(2) + "'");
    p.height = e.height = 400;
    panels.push_back(std::move(p));
    panels.push_back(std::move(e));
  }
  const auto png = dir / "record_response.png";
  util::write_png_panels(panels, png);
  return png;
}

std::filesystem::path shares_plot(const RunResidual& r, const std::filesystem::path& dir) {
  util::PlotSpec p("What explains the response error: NRMSE of the worst floor removed", "",
                   "NRMSE removed (%)");
  double x = 1.0;
  // Each bar is named under it (part, then effect) and in the legend with its share.
  const auto bar = [&](const std::string& label, const std::string& title, double value) {
    // A bar as a filled band from 0 (a single-point "boxes" series has no width).
    p.series.emplace_back(title, std::vector<double>{x - 0.35, x + 0.35},
                          std::vector<double>{100.0 * value, 100.0 * value},
                          "filledcurves y1=0 fs solid 0.8");
    p.x_labels.emplace_back(x, label);
    x += 1.0;
  };
  for (const auto* kind : {&r.links, &r.effects}) {
    for (const auto& s : *kind) {
      const std::string effect = s.effect == "all" ? "whole rig" : s.effect;
      bar(s.link + "\n" + effect,
          s.link + (s.effect == "all" ? " (its whole identified rig)" : ": " + s.effect) +
              ", share " + percent_text(s.share),
          s.removed);
    }
  }
  bar("remaining\nunexplained", "remaining: the identified model's NRMSE", r.identified);
  p.x_min = 0.3;
  p.x_max = x - 0.3;
  p.y_min = 0.0;
  const auto png = dir / "record_shares.png";
  util::write_png_plot(p, png);
  return png;
}

}  // namespace

std::vector<std::filesystem::path> write_run_plots(const RunIdentification& run,
                                                   const std::filesystem::path& dir) {
  std::filesystem::create_directories(dir);
  std::vector<std::filesystem::path> out;
  if (!run.links.empty()) out.push_back(lag_plot(run, dir));
  if (run.residual) {
    out.push_back(response_plot(*run.residual, dir));
    out.push_back(shares_plot(*run.residual, dir));
  }
  return out;
}

}  // namespace rths::identify
