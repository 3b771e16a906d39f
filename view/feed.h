#pragma once
// What the live view shows, built from the run record's entries (header, steps, events, footer)
// as the record's writer thread writes them (runtime::RecordObserver), or from a finished record.
// Never on the loop thread: the loop only appends to the record's ring.
//
// Inputs: RecordEntry values in record order. Per step, per actuator a: command c (m), realised
// (measured) displacement m (m), measured force f (N); per link: injected lag and round trip (s);
// lateness (s) and the overrun flag.
// Outputs (JSON, what the page draws; every name carries its unit):
//   samples   one every `stride` steps, stride = max(1, round(1 / (dt * points_per_second))): step,
//             time_s, command_mm, measured_mm, error_mm = (c - m), force_N, tracking indicator
//             ti_mm2, per DOF the measured response u_mm, the in-process prediction
//             predicted_u_mm and difference_mm = u - predicted (null where there is no
//             prediction), injected_ms / round_trip_ms per link, per link answer_age_steps
//             (the step minus the step its answer answered), answers (accepted so far) and
//             prediction_error_N (its force predictors' largest |error|; null: none),
//             diagnostics[link][channel]
//             (a controller's DIAGNOSTIC channels, SI; header.diagnostics names them),
//             lateness_ms, overruns and late
//             feedback so far. A sample holds the record's values of its step unchanged (only
//             scaled to mm/ms), so the page can be checked against the record step by step.
//   ti        tracking indicator (Mercan & Ricles 2007) at full rate, sign chosen so that lag
//             makes it grow: A_k = A_{k-1} + (m_k + m_{k-1})(c_k - c_{k-1}) / 2,
//             TA_k = TA_{k-1} + (c_k + c_{k-1})(m_k - m_{k-1}) / 2, TI_k = (TA_k - A_k) / 2 (mm^2).
//   spectra   every `spectrum_every` s of test time: the amplitude spectrum (mm) of the tracking
//             error e over the last N steps at full rate, N = the largest power of two <=
//             spectrum_seconds / dt (at least 64), Hann window w: A(f) = 2 |sum_k w_k e_k
//             e^{-2 pi i f dt k}| / sum_k w_k (a sine's amplitude at its frequency), at
//             log-spaced f = f_0 10^(i / spectrum_per_decade), f_0 = 1 / (N dt), up to
//             min(spectrum_max_hz, Nyquist): what a log frequency axis shows.
//   status    fail-safe state: "starting" before the first step ("refused" for a header whose
//             counts the view will not size its rings by, view/record_limits.h: the reason names
//             the field and its value), "armed" while stepping, "HOLD"
//             from a HOLD event on (its text is the reason), then from the footer: "failed" for
//             a real-time run that ran to its end but failed the one real-time verdict
//             (runtime::deadline_verdict on the rows' overruns and worst streak under the
//             header's deployment; the verdict is the reason), else "stopped" / "completed" (its
//             status and failed node); once finished, "verdict": the badge's words, colour
//             (level) and text (view/verdict.h: a real-time run that overran within its verdict
//             is a "warning", never a plain "completed") and the deadline diagnosis when one was
//             set (set_deadline_diagnosis); counters; the newest step and its CLOCK_REALTIME
//             start, from which the page tells how far behind the test it is.
//             With a prediction, per DOF, over the samples compared so far (the samples' steps,
//             not every step): the error measures `rths run` leads with, against the prediction
//             p, E_peak = 100 max|u - p| / max|p| and E_rms = 100 sqrt(sum (u - p)^2 / sum p^2)
//             (%, core/metrics.h; 0 while p is all 0), then the largest |u - p| and its root mean
//             square (mm).
//   events    the newest `max_events` events.
// Memory: every buffer is sized when the header arrives (rings), so a long run keeps a flat RSS.
// Thread safety: every member may be called from any thread.

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <mutex>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/simulation.h"
#include "runtime/record/record.h"
#include "view/verdict.h"

namespace rths::view {

struct FeedOptions {
  double points_per_second = 100.0;  // samples kept per simulated second
  std::size_t history = 60000;       // samples kept (a ring): 10 min at 100 per second
  double spectrum_every = 0.5;       // s of test time between spectra
  double spectrum_max_hz = 100.0;
  double spectrum_seconds = 4.0;      // s, at most: the window (its resolution is 1 / its length)
  double spectrum_per_decade = 20.0;  // frequencies shown per decade
  std::size_t spectra_kept = 1200;    // 10 min at one per 0.5 s
  std::size_t max_events = 500;
};

// Where a reader of the feed is: how many samples, spectra and events it has had.
struct FeedCursor {
  std::uint64_t samples = 0, spectra = 0, events = 0;
  bool header_sent = false;
};

class Feed : public runtime::RecordObserver {
 public:
  explicit Feed(FeedOptions options = {});

  // runtime::RecordObserver: parses one record frame's entry; an unreadable one is counted.
  void on_entry(std::string_view frame) override;
  void add(const runtime::RecordEntry& entry);

  // Facts about the run that are not in the record (critical-delay check, prediction), shown as
  // given; and a note (e.g. a truncated record's warning).
  void set_context(nlohmann::json context);
  nlohmann::json context() const {
    std::lock_guard lock(mutex_);
    return context_;
  }
  // The in-process prediction of the run (view/context.h): displacement per kept DOF (m) at
  // t_k = k dt, its columns the DOFs prediction.dofs names (empty: every DOF); each record
  // column is compared with the prediction of its DOF. Kept at the samples' steps only (every
  // stride-th, the stride from its dt as for the samples) in mm: steps / stride x kept values. Samples kept before it was set get it too,
  // and the difference statistics restart over the kept samples. A step the prediction does not
  // reach (it diverged) has none.
  void set_prediction(const core::SimulationResult& prediction);
  // Why a real-time record overran and what it is still good for (runtime::DeadlineDiagnosis's
  // describe(), as `rths launch` prints it), shown with the verdict. A finished record's only:
  // the diagnosis needs every step's work time, which a live feed does not keep.
  void set_deadline_diagnosis(std::string text);
  // How `rths launch` judged the case (view/verdict.h), before the footer arrives: the badge
  // then says it when the record's own verdict does not fail first.
  void set_judged(JudgedCase judged);
  // The record is complete (footer seen, or a finished record fully read): readers stop waiting.
  void finish();

  // Everything the reader at `cursor` has not had yet (all of it from a fresh cursor), and moves
  // the cursor. A reader that fell behind the rings gets the oldest kept.
  nlohmann::json since(FeedCursor& cursor) const;
  // Waits until something changed after `version`, the feed finished, or `timeout`.
  std::uint64_t wait_change(std::uint64_t version, std::chrono::milliseconds timeout) const;
  std::uint64_t version() const;
  bool finished() const;
  std::uint64_t steps_seen() const;
  std::uint64_t unreadable_entries() const;

 private:
  // The kept samples, a ring of options_.history rows in flat columns (row r of a per-actuator
  // column is at r * actuators_ + a; per link, r * links_ + l).
  struct Samples {
    std::vector<std::int64_t> step;
    std::vector<std::uint64_t> overruns, late;
    std::vector<double> time, lateness, command, measured, force, ti, injected, round_trip;
    // Per link: answer age (steps), answers accepted, largest |predictor error| (N); NaN: none.
    std::vector<double> answer_age, answers, prediction_error;
    std::vector<double> u, predicted;  // per DOF, mm (predicted: NaN where there is none)
    // A controller link's diagnostic channels (SI), r * diagnostics_ + diagnostic_offset_[l] + c.
    std::vector<double> diagnostics;
  };
  // Measured minus predicted at the compared samples, per DOF, mm.
  struct Difference {
    std::vector<double> max_abs, sum_squares;                      // of u - predicted
    std::vector<double> max_abs_predicted, sum_squares_predicted;  // of predicted
    std::uint64_t samples = 0;
    void reset(int dofs);
    void add(const double* u, const double* predicted, int dofs);
    nlohmann::json json() const;  // status "prediction" (header)
  };
  struct Spectrum {
    std::int64_t step = 0;
    double time = 0;
    std::vector<std::vector<double>> amplitude;  // [actuator][bin], mm
  };
  // A header refused_header (view/record_limits.h) refuses sizes nothing: the state is
  // "refused", the reason names its field, and no step is drawn.
  void on_header(const runtime::RunHeader& header);
  void on_step(const runtime::StepRecord& step);
  void on_event(const runtime::RunEvent& event);
  void on_footer(const runtime::RunFooter& footer);
  void track(const runtime::StepRecord& step);
  void keep_sample(const runtime::StepRecord& step);
  void link_sample(const runtime::StepRecord& step, const runtime::LinkSample& link, std::size_t i);
  // The prediction at `step` for `dof` (mm), NaN where there is none.
  double predicted(std::int64_t step, int dof) const;
  std::size_t setup_spectrum(double dt);
  void setup_diagnostics(const runtime::RunHeader& header);
  void compute_spectrum(const runtime::StepRecord& step);
  nlohmann::json header_json() const;
  nlohmann::json status_json() const;
  nlohmann::json samples_json(std::uint64_t from) const;
  nlohmann::json spectra_json(std::uint64_t from) const;
  void changed();

  FeedOptions options_;
  mutable std::mutex mutex_;
  mutable std::condition_variable change_;
  std::uint64_t version_ = 0;
  bool finished_ = false;
  std::uint64_t unreadable_ = 0;

  bool have_header_ = false;
  runtime::RunHeader header_;
  nlohmann::json context_;
  std::int64_t stride_ = 1;
  int actuators_ = 0, links_ = 0, dofs_ = 0;  // dofs_: the record's displacement columns
  std::vector<int> column_dofs_;              // the model DOF (0-based) of each displacement column
  // Per link: its controller's DIAGNOSTIC channels (names, in layout order) and where they start
  // in a sample row; diagnostics_: all links' channels.
  std::vector<std::vector<std::string>> diagnostic_names_;
  std::vector<std::size_t> diagnostic_offset_;
  std::size_t diagnostics_ = 0;

  // [row * prediction_dofs_ + column], mm; row = step / stride; column: that of a DOF among
  // prediction_kept_ (the DOFs the prediction kept, ascending; empty: every DOF, column = DOF).
  std::vector<double> prediction_;
  std::vector<int> prediction_kept_;
  std::int64_t prediction_stride_ = 1;
  int prediction_dofs_ = 0;
  Difference difference_;

  Samples samples_;
  std::size_t history_ = 1;
  std::uint64_t samples_total_ = 0;
  std::vector<Spectrum> spectra_;  // ring of options_.spectra_kept
  std::uint64_t spectra_total_ = 0;
  std::vector<runtime::RunEvent> events_;  // ring of options_.max_events
  std::uint64_t events_total_ = 0;

  // Full-rate state.
  std::uint64_t steps_ = 0, overruns_ = 0, late_ = 0;
  std::uint64_t overrun_streak_ = 0, worst_overrun_streak_ = 0;  // consecutive overrun rows
  double max_lateness_ = 0;
  std::int64_t last_step_ = -1, last_step_realtime_ns_ = 0;
  double last_time_ = 0;
  std::vector<double> prev_command_, prev_measured_, area_, transposed_area_, ti_;
  std::vector<std::vector<double>> error_ring_;       // [actuator][N], mm
  std::vector<double> window_, bins_hz_, cos_, sin_;  // cos_/sin_ per bin: of 2 pi f dt
  std::int64_t steps_per_spectrum_ = 1;

  // Fail-safe.
  std::string state_ = "starting", reason_, node_;
  bool have_footer_ = false;
  runtime::RunFooter footer_;
  ShownVerdict verdict_;
  std::string deadline_diagnosis_;
  std::optional<JudgedCase> judged_;
};

}  // namespace rths::view
