#include "identify/lab/report_plots.h"

#include <algorithm>

#include "identify/fit/effect_parameters.h"
#include "identify/lab/bode.h"
#include "identify/lab/report.h"
#include "util/plot.h"

namespace rths::identify {
namespace {

// Every `stride`-th sample of [begin, end) as x/y series.
util::Series series(const std::string& title, std::span<const double> x, std::span<const double> y,
                    std::size_t begin, std::size_t end, std::size_t max_points = 4000) {
  util::Series s;
  s.title = title;
  const std::size_t stride = std::max<std::size_t>(1, (end - begin) / max_points);
  for (std::size_t i = begin; i < end; i += stride) {
    s.x.push_back(x[i]);
    s.y.push_back(y[i]);
  }
  return s;
}

std::vector<double> residual(const ChannelSignals& s, const std::vector<double>& prediction) {
  std::vector<double> r(s.size());
  for (std::size_t i = 0; i < s.size(); ++i) r[i] = s.target[i] - prediction[i];
  return r;
}

// `s` with x and y multiplied by their scales (m -> mm: 1e3), for plots in the units a lab reads.
util::Series scaled(util::Series s, double x_scale, double y_scale) {
  for (double& x : s.x) x *= x_scale;
  for (double& y : s.y) y *= y_scale;
  return s;
}

// About `cycles` cycles of the command's dominant frequency in [lo, hi), ending at hi: a window a
// reader can follow (a whole held-out window of a 20 Hz test holds some 40 cycles).
std::size_t zoom_start(const ChannelSignals& s, std::size_t lo, std::size_t hi, double cycles) {
  const Spectrum spectrum =
      amplitude_spectrum(std::span<const double>(s.input).subspan(lo, hi - lo), s.dt);
  std::size_t peak = 1;
  for (std::size_t k = 1; k < spectrum.amplitude.size(); ++k)
    if (spectrum.amplitude[k] > spectrum.amplitude[peak]) peak = k;
  if (peak >= spectrum.frequency.size() || !(spectrum.frequency[peak] > 0)) return lo;
  const auto length = static_cast<std::size_t>(cycles / spectrum.frequency[peak] / s.dt);
  return hi - lo > length ? hi - length : lo;
}

// A window of about `seconds` inside the held-out samples with the largest input motion.
std::pair<std::size_t, std::size_t> heldout_window(const Identification& id,
                                                   const ChannelSignals& s, double seconds) {
  const auto width = static_cast<std::size_t>(std::max(10.0, seconds / s.dt));
  std::size_t best_start = id.split.heldout.front();
  double best = -1.0;
  const auto& held = id.split.heldout;
  for (std::size_t k = 0; k + width < held.size(); k += width / 2) {
    if (held[k + width] - held[k] != width) continue;  // window must be contiguous
    double sum = 0.0;
    for (std::size_t i = held[k]; i < held[k] + width; ++i) sum += s.velocity[i] * s.velocity[i];
    if (sum > best) {
      best = sum;
      best_start = held[k];
    }
  }
  return {best_start, std::min(s.size(), best_start + width)};
}

// The time-varying delay of the final model against the delay refitted window by window, with
// a band of two standard errors.
void write_delay_plot(const ChannelIdentification& c, const ChannelSignals& s,
                      const std::filesystem::path& png) {
  const SignalScales scales = signal_scales(s);
  const ChannelModel& model = c.final_fit.model;
  const ChannelModel constant = without_effect(model, Effect::kTimeVaryingDelay, scales);
  const auto delay_index = constant.index_of(Effect::kDelay, "delay", scales);
  if (!delay_index) return;
  const auto windows = windowed_estimate(constant, *delay_index, s, 16);
  util::Series estimate{"delay per window (fit)", {}, {}, "linespoints"};
  util::Series upper{"+2 std. error", {}, {}, "lines"}, lower{"-2 std. error", {}, {}, "lines"};
  for (const auto& w : windows) {
    estimate.x.push_back(w.time);
    estimate.y.push_back(w.value * 1e3);
    upper.x.push_back(w.time);
    upper.y.push_back((w.value + 2.0 * w.std_error) * 1e3);
    lower.x.push_back(w.time);
    lower.y.push_back((w.value - 2.0 * w.std_error) * 1e3);
  }
  const std::size_t first = base_params(model.channel, scales).size();
  std::size_t index = first;
  std::vector<double> coefficients;
  for (Effect e : model.effects) {
    const std::size_t count = effect_params(e, model.channel, scales).size();
    if (e == Effect::kTimeVaryingDelay) {
      coefficients.assign(model.params.begin() + static_cast<std::ptrdiff_t>(index),
                          model.params.begin() + static_cast<std::ptrdiff_t>(index + count));
    }
    index += count;
  }
  const double mean = model.param(Effect::kDelay, "delay", scales).value_or(0.0);
  const double t_mid = 0.5 * (s.time.front() + s.time.back());
  const double duration = std::max(s.time.back() - s.time.front(), s.dt);
  util::Series curve{"identified model tau(t)", {}, {}, "lines"};
  const std::size_t stride = std::max<std::size_t>(1, s.size() / 2000);
  for (std::size_t i = 0; i < s.size(); i += stride) {
    curve.x.push_back(s.time[i]);
    curve.y.push_back(
        std::max(0.0, mean + drift_profile(coefficients, (s.time[i] - t_mid) / duration)) * 1e3);
  }
  util::PlotSpec plot;
  plot.title =
      "actuator delay over the record: model and per-window estimate (band: +/- 2 std. error)";
  plot.xlabel = "time (s)";
  plot.ylabel = "delay (ms)";
  plot.series = {curve, estimate, upper, lower};
  util::write_png_plot(plot, png);
}

// The residual over time and its amplitude spectrum, before (declared) and after (final model).
void write_residual_plots(const ChannelIdentification& c, const ChannelSignals& s,
                          const std::filesystem::path& directory,
                          std::vector<std::filesystem::path>& written) {
  const auto r0 = residual(s, c.declared_fit.prediction);
  const auto r1 = residual(s, c.final_fit.prediction);
  const std::string name = channel_name(c.channel);
  const bool displacement = c.channel == Channel::kMeasured;
  const std::string unit = displacement ? "mm" : "N";
  const double to_unit = displacement ? 1e3 : 1.0;  // displacements in mm on every plot

  util::PlotSpec time_plot;
  time_plot.title = name + ": residual before (declared) and after (final model)";
  time_plot.xlabel = "time (s)";
  time_plot.ylabel = "residual (" + unit + ")";
  time_plot.series = {scaled(series("declared", s.time, r0, 0, s.size()), 1.0, to_unit),
                      scaled(series("final", s.time, r1, 0, s.size()), 1.0, to_unit)};
  written.push_back(directory / (name + "_residual_time.png"));
  util::write_png_plot(time_plot, written.back());

  const auto sp0 = amplitude_spectrum(r0, s.dt), sp1 = amplitude_spectrum(r1, s.dt);
  util::PlotSpec spectrum_plot;
  spectrum_plot.title = name + ": residual amplitude spectrum before and after";
  spectrum_plot.xlabel = "frequency (Hz)";
  spectrum_plot.ylabel = "amplitude (" + unit + ")";
  spectrum_plot.log_y = true;
  std::size_t cut = sp0.frequency.size();
  for (std::size_t k = 0; k < sp0.frequency.size(); ++k) {
    if (sp0.frequency[k] > std::min(50.0, 0.5 / s.dt)) {
      cut = k;
      break;
    }
  }
  spectrum_plot.series = {
      scaled(series("declared", sp0.frequency, sp0.amplitude, 1, cut), 1.0, to_unit),
      scaled(series("final", sp1.frequency, sp1.amplitude, 1, cut), 1.0, to_unit)};
  written.push_back(directory / (name + "_residual_spectrum.png"));
  util::write_png_plot(spectrum_plot, written.back());
}

// A figure of the held-out window [lo, hi) (samples): its title names the window in s.
util::PlotSpec held_out_plot(const std::string& what, const ChannelSignals& s, std::size_t lo,
                             std::size_t hi, const std::string& xlabel, const std::string& ylabel) {
  const std::string window = format_value(s.time[lo]) + "-" + format_value(s.time[hi - 1]) + " s";
  return {what + " (held-out window " + window + ")", xlabel, ylabel, {}};
}

void write_force_loops(const ChannelIdentification& c, const ChannelSignals& s, std::size_t lo,
                       std::size_t hi, const std::filesystem::path& directory,
                       std::vector<std::filesystem::path>& written) {
  util::PlotSpec loops = held_out_plot("force-displacement loops", s, lo, hi,
                                       "measured displacement (mm)", "force (N)");
  loops.series = {
      scaled(series("measured", s.input, s.target, lo, hi), 1e3, 1.0),
      scaled(series("declared model", s.input, c.declared_fit.prediction, lo, hi), 1e3, 1.0),
      scaled(series("final model", s.input, c.final_fit.prediction, lo, hi), 1e3, 1.0)};
  written.push_back(directory / "force_loops.png");
  util::write_png_plot(loops, written.back());
}

void write_tracking_plots(const ChannelIdentification& c, const ChannelSignals& s, std::size_t lo,
                          std::size_t hi, const std::filesystem::path& directory,
                          std::vector<std::filesystem::path>& written) {
  util::PlotSpec tracking =
      held_out_plot("actuator tracking", s, lo, hi, "time (s)", "displacement (mm)");
  const auto tracking_series = [&](std::size_t from) {
    return std::vector<util::Series>{
        scaled(series("command", s.time, s.input, from, hi), 1.0, 1e3),
        scaled(series("measured", s.time, s.target, from, hi), 1.0, 1e3),
        scaled(series("declared model", s.time, c.declared_fit.prediction, from, hi), 1.0, 1e3),
        scaled(series("final model", s.time, c.final_fit.prediction, from, hi), 1.0, 1e3)};
  };
  tracking.series = tracking_series(lo);
  util::PlotSpec zoom = tracking;
  const std::size_t from = zoom_start(s, lo, hi, 5.0);
  zoom.title =
      "zoom: the last " + format_value(s.time[hi - 1] - s.time[from]) + " s (about 5 cycles)";
  zoom.series = tracking_series(from);
  tracking.height = zoom.height = 420;
  written.push_back(directory / "measured_tracking.png");
  util::write_png_panels({tracking, zoom}, written.back());
  // A record too short for Welch averaging, or without a coherent band, has no Bode plot.
  std::optional<BodeData> bode;
  try {
    bode = actuator_bode(
        s, {{"identified model", &c.final_fit.model}, {"declared model", &c.declared_fit.model}});
  } catch (const std::invalid_argument&) {
    bode.reset();
  }
  if (bode) {
    written.push_back(directory / "measured_bode.png");
    write_bode_plot(*bode, written.back());
  }
}

}  // namespace

std::vector<std::filesystem::path> write_plots(const Identification& id,
                                               const std::filesystem::path& directory) {
  std::error_code ec;
  std::filesystem::create_directories(directory, ec);
  if (ec) throw std::runtime_error(directory.string() + ": cannot create: " + ec.message());
  std::vector<std::filesystem::path> written;
  for (const auto& c : id.channels) {
    const ChannelSignals& s = identified_signals(id, c.channel);
    write_residual_plots(c, s, directory, written);
    const auto [lo, hi] = heldout_window(id, s, 2.0);
    if (c.channel == Channel::kForce) {
      write_force_loops(c, s, lo, hi, directory, written);
    } else {
      write_tracking_plots(c, s, lo, hi, directory, written);
    }
  }
  if (const auto* c = id.find(Channel::kMeasured);
      c != nullptr && c->final_fit.model.has(Effect::kTimeVaryingDelay)) {
    written.push_back(directory / "measured_time_varying_delay.png");
    write_delay_plot(*c, identified_signals(id, Channel::kMeasured), written.back());
  }
  return written;
}

}  // namespace rths::identify
