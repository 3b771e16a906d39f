#include "view/feed.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <optional>

#include "runtime/record/node_health.h"
#include "runtime/record/realtime_verdict.h"
#include "view/record_limits.h"

namespace rths::view {
namespace {

constexpr double kMm = 1e3;  // m -> mm
constexpr double kMs = 1e3;  // s -> ms
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// Largest power of two <= seconds / dt, at least 64.
std::size_t spectrum_length(double dt, double seconds) {
  std::size_t n = 64;
  while (static_cast<double>(n * 2) * dt <= seconds + 1e-9) n *= 2;
  return n;
}

// Steps between kept samples: max(1, round(1 / (dt * points_per_second))).
std::int64_t sample_stride(double dt, double points_per_second) {
  return std::max<std::int64_t>(1, std::llround(1.0 / (dt * points_per_second)));
}

// Each controller node of the footer: its link line and its hold, frame by frame
// (runtime/record/node_health.h), for the page's "Controller link and hold" section.
nlohmann::json controllers_json(const runtime::RunFooter& footer) {
  nlohmann::json out = nlohmann::json::array();
  for (const runtime::NodeRejects& n : footer.node_rejects()) {
    if (!n.has_controller()) continue;
    nlohmann::json health = runtime::node_health_json(n)["controller"];
    out.push_back({{"node_id", n.node_id()},
                   {"label", n.label()},
                   {"link", runtime::controller_link_text(n)},
                   {"hold", health["hold"]}});
  }
  return out;
}

}  // namespace

Feed::Feed(FeedOptions options) : options_(options) {}

void Feed::on_entry(std::string_view frame) {
  runtime::RecordEntry entry;
  if (frame.size() < runtime::kRecordFrameHeaderBytes ||
      !entry.ParseFromArray(frame.data() + runtime::kRecordFrameHeaderBytes,
                            static_cast<int>(frame.size() - runtime::kRecordFrameHeaderBytes))) {
    std::lock_guard lock(mutex_);
    ++unreadable_;
    changed();
    return;
  }
  add(entry);
}

void Feed::add(const runtime::RecordEntry& entry) {
  std::lock_guard lock(mutex_);
  if (entry.has_header()) {
    // The copy a record repeats before its footer must not start the page over.
    if (!have_header_) on_header(entry.header());
  } else if (entry.has_step() && have_header_) {
    on_step(entry.step());
  } else if (entry.has_event()) {
    on_event(entry.event());
  } else if (entry.has_footer()) {
    on_footer(entry.footer());
  } else if (!entry.has_inputs()) {
    // (the run's inputs: the context, view/context.h, reads them; the page has no use for them)
    ++unreadable_;  // a step before any header cannot be drawn
  }
  changed();
}

void Feed::set_context(nlohmann::json context) {
  std::lock_guard lock(mutex_);
  context_ = std::move(context);
  changed();
}

void Feed::set_deadline_diagnosis(std::string text) {
  std::lock_guard lock(mutex_);
  deadline_diagnosis_ = std::move(text);
  changed();
}

void Feed::set_judged(JudgedCase judged) {
  std::lock_guard lock(mutex_);
  judged_ = std::move(judged);
}

void Feed::set_prediction(const core::SimulationResult& prediction) {
  std::lock_guard lock(mutex_);
  const double dt = prediction.dt > 0 ? prediction.dt : 1e-3;
  prediction_stride_ = sample_stride(dt, options_.points_per_second);
  prediction_dofs_ = static_cast<int>(prediction.displacement.cols());
  prediction_kept_ = prediction.dofs;
  const auto rows = static_cast<std::int64_t>(prediction.displacement.rows());
  prediction_.clear();
  prediction_.reserve(static_cast<std::size_t>((rows + prediction_stride_ - 1) /
                                               prediction_stride_ * prediction_dofs_));
  for (std::int64_t k = 0; k < rows; k += prediction_stride_)
    for (int d = 0; d < prediction_dofs_; ++d)
      prediction_.push_back(prediction.displacement(k, d) * kMm);
  difference_.reset(dofs_);
  const auto D = static_cast<std::size_t>(dofs_);
  const std::uint64_t first = samples_total_ > history_ ? samples_total_ - history_ : 0;
  for (std::uint64_t i = first; i < samples_total_ && D > 0; ++i) {
    const std::size_t r = static_cast<std::size_t>(i % history_);
    for (std::size_t d = 0; d < D; ++d)
      samples_.predicted[r * D + d] = predicted(samples_.step[r], column_dofs_[d]);
    difference_.add(&samples_.u[r * D], &samples_.predicted[r * D], dofs_);
  }
  changed();
}

double Feed::predicted(std::int64_t step, int dof) const {
  const int column = prediction_column(prediction_kept_, prediction_dofs_, dof);
  if (step < 0 || step % prediction_stride_ != 0 || column < 0) return kNaN;
  const auto i = static_cast<std::size_t>(step / prediction_stride_ * prediction_dofs_ + column);
  return i < prediction_.size() ? prediction_[i] : kNaN;
}

void Feed::Difference::reset(int dofs) {
  for (auto* v : {&max_abs, &sum_squares, &max_abs_predicted, &sum_squares_predicted})
    v->assign(static_cast<std::size_t>(dofs), 0.0);
  samples = 0;
}

// One sample; one without a prediction at every DOF is not compared.
void Feed::Difference::add(const double* u, const double* predicted, int dofs) {
  for (int d = 0; d < dofs; ++d)
    if (std::isnan(predicted[d])) return;
  for (int d = 0; d < dofs; ++d) {
    const auto i = static_cast<std::size_t>(d);
    const double e = u[d] - predicted[d];
    max_abs[i] = std::max(max_abs[i], std::abs(e));
    sum_squares[i] += e * e;
    max_abs_predicted[i] = std::max(max_abs_predicted[i], std::abs(predicted[d]));
    sum_squares_predicted[i] += predicted[d] * predicted[d];
  }
  ++samples;
}

nlohmann::json Feed::Difference::json() const {
  const auto n = static_cast<double>(samples);
  nlohmann::json peak = nlohmann::json::array(), rms = nlohmann::json::array(),
                 rms_mm = nlohmann::json::array();
  for (std::size_t d = 0; d < max_abs.size(); ++d) {
    const auto percent = [](double error, double scale) {
      return scale > 0.0 ? 100.0 * error / scale : 0.0;
    };
    peak.push_back(percent(max_abs[d], max_abs_predicted[d]));
    rms.push_back(percent(std::sqrt(sum_squares[d]), std::sqrt(sum_squares_predicted[d])));
    rms_mm.push_back(std::sqrt(sum_squares[d] / n));
  }
  return {{"compared_samples", samples},
          {"peak_error_pct", peak},
          {"rms_error_pct", rms},
          {"max_abs_difference_mm", max_abs},
          {"rms_difference_mm", rms_mm}};
}

void Feed::finish() {
  std::lock_guard lock(mutex_);
  finished_ = true;
  changed();
}

void Feed::changed() {
  ++version_;
  change_.notify_all();
}

void Feed::on_header(const runtime::RunHeader& header) {
  if (const auto why = refused_header(header)) {  // nothing is sized from it: no page, the reason
    state_ = "refused";
    reason_ = *why;
    return;
  }
  header_ = header;
  have_header_ = true;
  actuators_ = header.actuators();
  links_ = header.link_node_ids_size();
  column_dofs_ = runtime::recorded_dofs(header);
  dofs_ = static_cast<int>(column_dofs_.size());
  const double dt = header.dt() > 0 ? header.dt() : 1e-3;
  stride_ = sample_stride(dt, options_.points_per_second);
  history_ = std::max<std::size_t>(options_.history, 1);
  samples_.step.assign(history_, 0);
  samples_.overruns.assign(history_, 0);
  samples_.late.assign(history_, 0);
  for (auto* v : {&samples_.time, &samples_.lateness}) v->assign(history_, 0.0);
  for (auto* v : {&samples_.u, &samples_.predicted})
    v->assign(history_ * static_cast<std::size_t>(dofs_), 0.0);
  difference_.reset(dofs_);
  for (auto* v : {&samples_.command, &samples_.measured, &samples_.force, &samples_.ti})
    v->assign(history_ * static_cast<std::size_t>(actuators_), 0.0);
  for (auto* v : {&samples_.injected, &samples_.round_trip, &samples_.answer_age, &samples_.answers,
                  &samples_.prediction_error})
    v->assign(history_ * static_cast<std::size_t>(links_), 0.0);
  setup_diagnostics(header);
  const std::size_t n = setup_spectrum(dt);
  error_ring_.assign(actuators_, std::vector<double>(n, 0.0));
  spectra_.assign(
      std::max<std::size_t>(options_.spectra_kept, 1),
      Spectrum{0, 0,
               std::vector<std::vector<double>>(actuators_, std::vector<double>(bins_hz_.size()))});
  steps_per_spectrum_ = std::max<std::int64_t>(1, std::llround(options_.spectrum_every / dt));
  for (auto* v : {&prev_command_, &prev_measured_, &area_, &transposed_area_, &ti_})
    v->assign(actuators_, 0.0);
  events_.assign(std::max<std::size_t>(options_.max_events, 1), runtime::RunEvent{});
}

// Each link's controller diagnostic channels, from the header's deployment (a CONTROLLER node's
// DIAGNOSTIC feedback fields), and their room in the sample ring.
void Feed::setup_diagnostics(const runtime::RunHeader& header) {
  diagnostic_names_.assign(static_cast<std::size_t>(links_), {});
  diagnostic_offset_.assign(static_cast<std::size_t>(links_), 0);
  diagnostics_ = 0;
  for (int l = 0; l < links_; ++l) {
    diagnostic_offset_[static_cast<std::size_t>(l)] = diagnostics_;
    for (const auto& node : header.study().deployment().nodes()) {
      if (node.id() != header.link_node_ids(l) || !node.has_controller()) continue;
      for (const auto& f : node.controller().feedback().fields())
        if (f.role() == config::FrameField::DIAGNOSTIC)
          diagnostic_names_[static_cast<std::size_t>(l)].push_back(
              f.name() + (f.unit().empty() ? "" : " (SI; frame " + f.unit() + ")"));
    }
    diagnostics_ += diagnostic_names_[static_cast<std::size_t>(l)].size();
  }
  samples_.diagnostics.assign(history_ * diagnostics_, 0.0);
}

// Full-rate tracking indicator and error ring, per actuator.
void Feed::track(const runtime::StepRecord& step) {
  const int n = std::min({actuators_, step.command_size(), step.realised_size()});
  for (int a = 0; a < n; ++a) {
    const double c = step.command(a) * kMm, m = step.realised(a) * kMm;
    if (steps_ > 0) {
      area_[a] += 0.5 * (m + prev_measured_[a]) * (c - prev_command_[a]);
      transposed_area_[a] += 0.5 * (c + prev_command_[a]) * (m - prev_measured_[a]);
      ti_[a] = 0.5 * (transposed_area_[a] - area_[a]);
    }
    prev_command_[a] = c;
    prev_measured_[a] = m;
    std::vector<double>& ring = error_ring_[a];
    ring[static_cast<std::size_t>(steps_) % ring.size()] = c - m;
  }
}

void Feed::on_step(const runtime::StepRecord& step) {
  track(step);
  ++steps_;
  if (step.overrun()) ++overruns_;
  overrun_streak_ = step.overrun() ? overrun_streak_ + 1 : 0;
  worst_overrun_streak_ = std::max(worst_overrun_streak_, overrun_streak_);
  for (const auto& link : step.links())
    if (link.answered_step() < step.step()) {
      ++late_;
      break;
    }
  max_lateness_ = std::max(max_lateness_, step.lateness());
  last_step_ = step.step();
  last_time_ = step.time();
  if (step.start_realtime_ns() != 0) last_step_realtime_ns_ = step.start_realtime_ns();
  if (state_ == "starting") state_ = "armed";
  if (steps_ >= window_.size() && step.step() % steps_per_spectrum_ == 0) compute_spectrum(step);
  if (step.step() % stride_ == 0) keep_sample(step);
}

void Feed::keep_sample(const runtime::StepRecord& step) {
  Samples& s = samples_;
  const std::size_t r = static_cast<std::size_t>(samples_total_ % history_);
  s.step[r] = step.step();
  s.time[r] = step.time();
  const auto D = static_cast<std::size_t>(dofs_);
  for (std::size_t d = 0; d < D; ++d) {
    const int i = static_cast<int>(d);
    s.u[r * D + d] = i < step.displacement_size() ? step.displacement(i) * kMm : 0;
    s.predicted[r * D + d] = predicted(step.step(), column_dofs_[d]);
  }
  if (D > 0) difference_.add(&s.u[r * D], &s.predicted[r * D], dofs_);
  s.lateness[r] = step.lateness() * kMs;
  s.overruns[r] = overruns_;
  s.late[r] = late_;
  for (int a = 0; a < actuators_; ++a) {
    const std::size_t i = r * static_cast<std::size_t>(actuators_) + static_cast<std::size_t>(a);
    s.command[i] = a < step.command_size() ? step.command(a) * kMm : 0;
    s.measured[i] = a < step.realised_size() ? step.realised(a) * kMm : 0;
    s.force[i] = a < step.measured_force_size() ? step.measured_force(a) : 0;
    s.ti[i] = ti_[a];
  }
  for (int l = 0; l < links_; ++l) {
    const std::size_t i = r * static_cast<std::size_t>(links_) + static_cast<std::size_t>(l);
    s.injected[i] = l < step.links_size() ? step.links(l).injected_lag() * kMs : 0;
    s.round_trip[i] = l < step.links_size() ? step.links(l).round_trip() * kMs : 0;
    s.answer_age[i] = s.answers[i] = s.prediction_error[i] = kNaN;
    if (l < step.links_size()) link_sample(step, step.links(l), i);
    const auto names = diagnostic_names_[static_cast<std::size_t>(l)].size();
    for (std::size_t c = 0; c < names; ++c) {
      const bool has = l < step.links_size() &&
                       static_cast<int>(c) < step.links(l).controller_diagnostics_size();
      s.diagnostics[r * diagnostics_ + diagnostic_offset_[static_cast<std::size_t>(l)] + c] =
          has ? step.links(l).controller_diagnostics(static_cast<int>(c))
              : std::numeric_limits<double>::quiet_NaN();
    }
  }
  ++samples_total_;
}

// A link's answer age (steps: the step minus the step its answer answered; NaN before the
// first answer), the answers accepted so far (NaN when not counted) and the largest |error| of
// its force predictors (N; NaN without one), into sample column i.
void Feed::link_sample(const runtime::StepRecord& step, const runtime::LinkSample& link,
                       std::size_t i) {
  if (link.answered_step() > 0)
    samples_.answer_age[i] = static_cast<double>(step.step() - link.answered_step());
  if (link.answers() > 0) samples_.answers[i] = static_cast<double>(link.answers());
  for (const double e : link.prediction_error())
    samples_.prediction_error[i] = std::isnan(samples_.prediction_error[i])
                                       ? std::abs(e)
                                       : std::max(samples_.prediction_error[i], std::abs(e));
}

// The Hann window (normalised so that 2 |X(f)| is a sine's amplitude) and the log-spaced
// frequencies with each one's rotation per step; returns the window's length.
std::size_t Feed::setup_spectrum(double dt) {
  const std::size_t n = spectrum_length(dt, options_.spectrum_seconds);
  window_.resize(n);
  double sum = 0;
  for (std::size_t i = 0; i < n; ++i)
    sum += window_[i] = 0.5 - 0.5 * std::cos(2 * std::numbers::pi * static_cast<double>(i) /
                                             static_cast<double>(n));
  for (double& w : window_) w /= sum;
  const double lowest = 1.0 / (static_cast<double>(n) * dt);
  const double top = std::min(options_.spectrum_max_hz, 0.5 / dt);
  bins_hz_.clear();
  cos_.clear();
  sin_.clear();
  for (int i = 0;; ++i) {
    const double f = lowest * std::pow(10.0, i / options_.spectrum_per_decade);
    if (f > top * (1 + 1e-12)) break;
    bins_hz_.push_back(f);
    cos_.push_back(std::cos(2 * std::numbers::pi * f * dt));
    sin_.push_back(std::sin(2 * std::numbers::pi * f * dt));
  }
  return n;
}

// Direct DTFT of the windowed error at the few log-spaced frequencies shown (~45 for two decades;
// a full FFT would compute thousands of bins the axis cannot show), e^{-2 pi i f dt k} by rotation.
void Feed::compute_spectrum(const runtime::StepRecord& step) {
  Spectrum& out = spectra_[spectra_total_ % spectra_.size()];
  out.step = step.step();
  out.time = step.time();
  const std::size_t n = window_.size();
  const std::size_t oldest = static_cast<std::size_t>(steps_) % n;  // ring index of the oldest
  for (int a = 0; a < actuators_; ++a) {
    const std::vector<double>& ring = error_ring_[a];
    for (std::size_t j = 0; j < bins_hz_.size(); ++j) {
      double re = 0, im = 0, zr = 1, zi = 0;  // z = e^{-2 pi i f dt k}
      for (std::size_t i = 0; i < n; ++i) {
        const double x = ring[(oldest + i) % n] * window_[i];
        re += x * zr;
        im += x * zi;
        const double next = zr * cos_[j] + zi * sin_[j];
        zi = zi * cos_[j] - zr * sin_[j];
        zr = next;
      }
      out.amplitude[a][j] = 2 * std::hypot(re, im);
    }
  }
  ++spectra_total_;
}

void Feed::on_event(const runtime::RunEvent& event) {
  if (!events_.empty()) events_[events_total_ % events_.size()] = event;
  ++events_total_;
  const std::string& what = event.what();
  if (what.rfind("HOLD", 0) == 0) {  // the coordinator's "HOLD sent to the <receivers>: why"
    if (state_ != "HOLD") reason_ = what;
    state_ = "HOLD";
  }
}

void Feed::on_footer(const runtime::RunFooter& footer) {
  footer_ = footer;
  have_footer_ = true;
  // The record's own rows judged by the one real-time verdict, as the coordinator judged its run
  // and identify judges the record: a run that failed it is never shown as completed.
  FinishedRun run;
  run.footer = footer;
  run.real_time = header_.clock() == "real_time";
  run.counts = {steps_ > 0 ? steps_ - 1 : 0, overruns_, worst_overrun_streak_};
  run.rule = runtime::deadline_rule(header_.study().deployment(), header_.dt());
  run.platform_overridden = header_.platform().accepted_override();
  run.platform_verdict = header_.platform().verdict();
  run.judged = judged_;
  verdict_ = shown_verdict(run);
  state_ = verdict_.state;
  reason_ = footer.ok() && verdict_.state == "failed" ? verdict_.text : footer.status();
  node_ = footer.failed_node();
  overruns_ = std::max<std::uint64_t>(overruns_, footer.counters().overruns());
  finished_ = true;
}

// ---- JSON: what the page reads ----

nlohmann::json Feed::header_json() const {
  nlohmann::json h = {{"run_id", header_.run_id()},
                      {"case", header_.case_name()},
                      {"clock", header_.clock()},
                      {"dt_s", header_.dt()},
                      {"dofs", header_.dofs()},
                      {"actuators", actuators_},
                      {"links", header_.link_node_ids()},
                      {"stride_steps", stride_},
                      {"start_realtime_ns", header_.start_realtime_ns()},
                      {"study", header_.study().name()},
                      {"spectrum_hz", bins_hz_},
                      {"spectrum_window_steps", window_.size()},
                      {"spectrum_window_s", static_cast<double>(window_.size()) * header_.dt()}};
  const bool floors = !header_.study().structure().has_matrices();
  for (int d = 0; d < dofs_; ++d)
    h["dof_labels"].push_back((floors ? "floor " : "DOF ") +
                              std::to_string(column_dofs_[static_cast<std::size_t>(d)] + 1));
  for (const auto& node : header_.study().deployment().nodes())
    h["link_labels"][std::to_string(node.id())] = config::NodeSpec::Kind_Name(node.kind());
  h["diagnostics"] = diagnostic_names_;  // per link: its controller's channel names
  return h;
}

nlohmann::json Feed::status_json() const {
  nlohmann::json s = {{"state", state_},
                      {"reason", reason_},
                      {"node", node_},
                      {"steps", steps_},
                      {"latest_step", last_step_},
                      {"latest_time_s", last_time_},
                      {"latest_step_realtime_ns", last_step_realtime_ns_},
                      {"overruns", overruns_},
                      {"late_feedback", late_},
                      {"max_lateness_ms", max_lateness_ * kMs},
                      {"finished", finished_},
                      {"unreadable_entries", unreadable_}};
  if (have_footer_) {
    s["verdict"] = {{"level", verdict_.level},
                    {"badge", verdict_.badge},
                    {"text", verdict_.text},
                    {"diagnosis", deadline_diagnosis_}};
    const auto& c = footer_.counters();
    s["footer"] = {{"ok", footer_.ok()},
                   {"status", footer_.status()},
                   {"failed_node", footer_.failed_node()},
                   {"diverged", footer_.diverged()},
                   {"wall_seconds", footer_.wall_seconds()},
                   {"overruns", c.overruns()},
                   {"late_feedback", c.late_feedback()},
                   {"steps", c.steps()}};
    s["controllers"] = controllers_json(footer_);
  }
  if (difference_.samples > 0) s["prediction"] = difference_.json();
  return s;
}

namespace {

// `count` empty arrays under each of `names`.
void empty_columns(nlohmann::json& j, std::initializer_list<const char*> names, int count) {
  for (const char* name : names) {
    j[name] = nlohmann::json::array();
    for (int i = 0; i < count; ++i) j[name].push_back(nlohmann::json::array());
  }
}

}  // namespace

nlohmann::json Feed::samples_json(std::uint64_t from) const {
  nlohmann::json j;
  empty_columns(j, {"step", "time_s", "lateness_ms", "overruns", "late_feedback"}, 0);
  empty_columns(j, {"command_mm", "measured_mm", "error_mm", "force_N", "ti_mm2"}, actuators_);
  empty_columns(
      j, {"injected_ms", "round_trip_ms", "answer_age_steps", "answers", "prediction_error_N"},
      links_);
  empty_columns(j, {"u_mm", "predicted_u_mm", "difference_mm"}, dofs_);
  j["diagnostics"] = nlohmann::json::array();  // [link][channel]: SI, NaN (null) where absent
  for (const auto& names : diagnostic_names_) {
    nlohmann::json channels = nlohmann::json::array();
    for (std::size_t c = 0; c < names.size(); ++c) channels.push_back(nlohmann::json::array());
    j["diagnostics"].push_back(channels);
  }
  const Samples& s = samples_;
  const auto A = static_cast<std::size_t>(actuators_), L = static_cast<std::size_t>(links_);
  const auto D = static_cast<std::size_t>(dofs_);
  for (std::uint64_t i = from; i < samples_total_; ++i) {
    const std::size_t r = static_cast<std::size_t>(i % history_);
    j["step"].push_back(s.step[r]);
    j["time_s"].push_back(s.time[r]);
    for (std::size_t a = 0; a < A; ++a) {
      j["command_mm"][a].push_back(s.command[r * A + a]);
      j["measured_mm"][a].push_back(s.measured[r * A + a]);
      j["error_mm"][a].push_back(s.command[r * A + a] - s.measured[r * A + a]);
      j["force_N"][a].push_back(s.force[r * A + a]);
      j["ti_mm2"][a].push_back(s.ti[r * A + a]);
    }
    for (std::size_t l = 0; l < L; ++l) {
      j["injected_ms"][l].push_back(s.injected[r * L + l]);
      j["round_trip_ms"][l].push_back(s.round_trip[r * L + l]);
      j["answer_age_steps"][l].push_back(s.answer_age[r * L + l]);
      j["answers"][l].push_back(s.answers[r * L + l]);
      j["prediction_error_N"][l].push_back(s.prediction_error[r * L + l]);
    }
    for (std::size_t d = 0; d < D; ++d) {  // NaN (no prediction) is written as null
      j["u_mm"][d].push_back(s.u[r * D + d]);
      j["predicted_u_mm"][d].push_back(s.predicted[r * D + d]);
      j["difference_mm"][d].push_back(s.u[r * D + d] - s.predicted[r * D + d]);
    }
    for (std::size_t l = 0; l < L; ++l)
      for (std::size_t c = 0; c < diagnostic_names_[l].size(); ++c)
        j["diagnostics"][l][c].push_back(
            s.diagnostics[r * diagnostics_ + diagnostic_offset_[l] + c]);
    j["lateness_ms"].push_back(s.lateness[r]);
    j["overruns"].push_back(s.overruns[r]);
    j["late_feedback"].push_back(s.late[r]);
  }
  return j;
}

nlohmann::json Feed::spectra_json(std::uint64_t from) const {
  nlohmann::json list = nlohmann::json::array();
  for (std::uint64_t i = from; i < spectra_total_; ++i) {
    const Spectrum& s = spectra_[i % spectra_.size()];
    list.push_back({{"step", s.step}, {"time_s", s.time}, {"amplitude_mm", s.amplitude}});
  }
  return list;
}

nlohmann::json Feed::since(FeedCursor& cursor) const {
  std::lock_guard lock(mutex_);
  nlohmann::json j = {{"version", version_}, {"status", status_json()}};
  if (!have_header_) return j;
  if (!cursor.header_sent) {
    j["header"] = header_json();
    j["context"] = context_;
    cursor.header_sent = true;
  }
  const auto oldest = [](std::uint64_t total, std::size_t ring) {
    return total > ring ? total - ring : 0;
  };
  const std::uint64_t first = std::max(cursor.samples, oldest(samples_total_, history_));
  j["samples"] = samples_json(first);
  cursor.samples = samples_total_;
  j["spectra"] = spectra_json(std::max(cursor.spectra, oldest(spectra_total_, spectra_.size())));
  cursor.spectra = spectra_total_;
  j["events"] = nlohmann::json::array();
  for (std::uint64_t i = std::max(cursor.events, oldest(events_total_, events_.size()));
       i < events_total_; ++i) {
    const auto& e = events_[i % events_.size()];
    j["events"].push_back(
        {{"step", e.step()}, {"what", e.what()}, {"realtime_ns", e.realtime_ns()}});
  }
  cursor.events = events_total_;
  return j;
}

std::uint64_t Feed::wait_change(std::uint64_t version, std::chrono::milliseconds timeout) const {
  std::unique_lock lock(mutex_);
  change_.wait_for(lock, timeout, [&] { return version_ != version || finished_; });
  return version_;
}

std::uint64_t Feed::version() const {
  std::lock_guard lock(mutex_);
  return version_;
}

bool Feed::finished() const {
  std::lock_guard lock(mutex_);
  return finished_;
}

std::uint64_t Feed::steps_seen() const {
  std::lock_guard lock(mutex_);
  return steps_;
}

std::uint64_t Feed::unreadable_entries() const {
  std::lock_guard lock(mutex_);
  return unreadable_;
}

}  // namespace rths::view
