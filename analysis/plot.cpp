#include "analysis/plot.h"

#include <cmath>
#include <cstdio>
#include <memory>
#include <sstream>
#include <stdexcept>

namespace rths::analysis {
namespace {

std::string quoted(const std::string& text) {
  std::string out = "\"";
  for (char c : text) {
    if (c == '"' || c == '\\') out += '\\';
    out += c;
  }
  return out + "\"";
}

void append_panel(std::ostringstream& script, const PlotSpec& spec) {
  script << "set title " << quoted(spec.title) << "\n"
         << "set xlabel " << quoted(spec.xlabel) << "\n"
         << "set ylabel " << quoted(spec.ylabel) << "\n"
         << (spec.log_y ? "set logscale y\n" : "unset logscale y\n") << "plot ";
  for (std::size_t i = 0; i < spec.series.size(); ++i) {
    script << (i ? ", " : "") << "'-' using 1:2 with " << spec.series[i].style << " title "
           << quoted(spec.series[i].title);
  }
  script << "\n";
  script.precision(10);
  for (const Series& s : spec.series) {
    for (std::size_t k = 0; k < s.x.size() && k < s.y.size(); ++k) {
      // gnuplot cannot draw non-finite points (and zero on a log axis); leave a gap instead.
      if (std::isfinite(s.x[k]) && std::isfinite(s.y[k]) && !(spec.log_y && s.y[k] <= 0)) {
        script << s.x[k] << ' ' << s.y[k] << '\n';
      } else {
        script << '\n';
      }
    }
    script << "e\n";
  }
}

void run_gnuplot(const std::string& script, const std::filesystem::path& png) {
  struct PipeCloser {
    void operator()(FILE* f) const { if (f) pclose(f); }
  };
  FILE* pipe = popen("gnuplot 2>/dev/null", "w");
  if (pipe == nullptr) throw std::runtime_error("cannot start gnuplot for " + png.string());
  const std::size_t written = std::fwrite(script.data(), 1, script.size(), pipe);
  const int status = pclose(pipe);
  if (written != script.size() || status != 0) {
    throw std::runtime_error("gnuplot failed to write " + png.string() +
                             " (is gnuplot-nox installed?)");
  }
}

}  // namespace

void write_png_plot(const PlotSpec& spec, const std::filesystem::path& png) {
  write_png_panels({spec}, png);
}

void write_png_panels(const std::vector<PlotSpec>& panels, const std::filesystem::path& png) {
  if (panels.empty()) throw std::invalid_argument("no panels to plot into " + png.string());
  std::ostringstream script;
  const int height = panels.front().height * static_cast<int>(panels.size());
  script << "set terminal pngcairo size " << panels.front().width << "," << height
         << " font 'sans,10'\n"
         << "set output " << quoted(png.string()) << "\n"
         << "set termoption noenhanced\nset grid\nset key top right\n";
  if (panels.size() > 1) script << "set multiplot layout " << panels.size() << ",1\n";
  for (const PlotSpec& panel : panels) append_panel(script, panel);
  if (panels.size() > 1) script << "unset multiplot\n";
  script << "set output\n";
  run_gnuplot(script.str(), png);
}

}  // namespace rths::analysis
