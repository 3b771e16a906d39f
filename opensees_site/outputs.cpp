#include "opensees_site/outputs.h"

#include <string>

#include "results/results.h"
#include "results/write.h"
#include "runtime/record/measurements.h"
#include "util/plot.h"

namespace rths::opensees {

namespace {

std::vector<double> column(const core::Mat& m, int c, double scale) {
  std::vector<double> v(static_cast<std::size_t>(m.rows()));
  for (Eigen::Index k = 0; k < m.rows(); ++k) v[static_cast<std::size_t>(k)] = scale * m(k, c);
  return v;
}

std::vector<double> scaled(const std::vector<double>& v, double scale) {
  std::vector<double> out(v);
  for (double& x : out) x *= scale;
  return out;
}

util::PlotSpec spec(std::string title, std::string xlabel, std::string ylabel) {
  util::PlotSpec p;
  p.title = std::move(title);
  p.xlabel = std::move(xlabel);
  p.ylabel = std::move(ylabel);
  return p;
}

void write_plots(const runtime::RunMeasurements& m, const std::filesystem::path& out) {
  const core::SimulationResult& r = m.steps;
  util::PlotSpec drift = spec("Commanded and realised drift (" + m.case_name + ", " + m.clock + ")",
                              "time (s)", "drift (mm)");
  util::PlotSpec loop = spec("Measured force against realised drift (" + m.case_name + ")",
                             "realised drift (mm)", "force (kN)");
  for (int a = 0; a < r.command.cols(); ++a) {
    const std::string name = "actuator " + std::to_string(a + 1);
    drift.series.push_back({name + " commanded", r.time, column(r.command, a, 1e3)});
    drift.series.push_back({name + " realised", r.time, column(r.realised, a, 1e3)});
    loop.series.push_back({name, column(r.realised, a, 1e3), column(r.measured_force, a, 1e-3)});
  }
  util::write_png_plot(drift, out / "command_realised.png");
  util::write_png_plot(loop, out / "force_displacement.png");
  util::PlotSpec lag = spec("Round trip per link", "time (s)", "round trip (ms)");
  for (const auto& [id, link] : m.links) {
    const std::string name = "node " + std::to_string(id);
    lag.series.push_back({name + " measured", link.time, scaled(link.round_trip, 1e3)});
    lag.series.push_back({name + " injected", link.time, scaled(link.injected, 1e3)});
  }
  if (!lag.series.empty()) util::write_png_plot(lag, out / "lag.png");
}

}  // namespace

void write_site_outputs(const std::filesystem::path& record, const std::filesystem::path& out,
                        bool plots) {
  const runtime::RecordContents contents = runtime::read_record(record);
  results::write_table(results::record_table(contents), out / "results.csv", results::Format::kCsv);
  if (plots) write_plots(runtime::measure_run(contents), out);
}

}  // namespace rths::opensees
