#include "opensees_site/session.h"

#include <algorithm>
#include <cmath>

#include "coordinator/coordinator.h"

namespace rths::opensees {

namespace {

std::string seconds_text(std::chrono::nanoseconds d) {
  return std::to_string(std::chrono::duration<double>(d).count()) + " s";
}

}  // namespace

Session::Session(Connection& connection, const BasicMapping& mapping, SessionOptions options)
    : connection_(connection),
      mapping_(mapping),
      options_(std::move(options)),
      n_(mapping.basic_dofs()),
      in_(static_cast<std::size_t>(options_.frame_size), 0.0),
      out_(static_cast<std::size_t>(options_.frame_size), 0.0),
      trial_(static_cast<std::size_t>(3 * n_ + 1), 0.0),
      commanded_(trial_),
      drift_(core::Vec::Zero(mapping.actuators())),
      u_(core::Vec::Zero(options_.dofs)),
      v_(core::Vec::Zero(options_.dofs)),
      a_(core::Vec::Zero(options_.dofs)) {
  // A client that stops reading its answers is as lost as one that stops sending: the same
  // window, then HOLD, rather than a site blocked in send().
  connection_.set_send_timeout(options_.frame_timeout);
}

void Session::refuse(const std::string& why) const {
  // The connection ends now: a client that checks its reads learns at once that no answer will
  // come. (OpenSees 3.8's TCP_Socket does not: it loops on a closed socket until stopped.)
  connection_.end();
  throw coordinator::RunAborted(options_.client + ": " + why, options_.client);
}

bool Session::read_frame() {
  const bool started = step_ > 0 || step_open_;
  const auto timeout = started ? options_.frame_timeout : options_.first_frame_timeout;
  const std::size_t bytes = in_.size() * sizeof(double);
  const Connection::ReadResult r = connection_.read_exact(in_.data(), bytes, timeout);
  const std::string where = " (after step " + std::to_string(step_) + ")";
  switch (r.status) {
    case Connection::Read::kComplete: return true;
    case Connection::Read::kClosed:
      if (step_open_)
        refuse("closed the connection inside step " + std::to_string(step_) +
               ", before committing it");
      return false;
    case Connection::Read::kTruncated:
      refuse("truncated frame: " + std::to_string(r.bytes) + " of " + std::to_string(bytes) +
             " bytes, then the connection closed" + where);
    case Connection::Read::kTimedOut:
      if (r.bytes > 0)
        refuse("truncated frame: " + std::to_string(r.bytes) + " of " + std::to_string(bytes) +
               " bytes, then nothing for " + seconds_text(timeout) + where);
      refuse("sent nothing for " + seconds_text(timeout) + where + "; the limit is " +
             (started ? options_.frame_timeout_reason : std::string("the start-up timeout")));
  }
  return false;
}

void Session::store_trial() {
  try {
    check_trial_frame(in_, n_);
  } catch (const ProtocolError& e) {
    refuse(e.what());
  }
  std::copy_n(in_.begin() + 1, trial_.size(), trial_.begin());
  have_trial_ = true;
}

void Session::answer() {
  try {
    connection_.write_all(out_.data(), out_.size() * sizeof(double));
  } catch (const std::runtime_error& e) {
    refuse(e.what());  // named as the client's fault: HOLD, STOP, the record closed
  }
}

void Session::answer_matrix(const core::Mat* matrix) {
  std::fill(out_.begin(), out_.end(), 0.0);
  if (matrix)  // column-major, as OpenSees' Matrix stores it
    for (int j = 0; j < n_; ++j)
      for (int i = 0; i < n_; ++i) out_[static_cast<std::size_t>(j * n_ + i)] = (*matrix)(i, j);
  answer();
}

void Session::command_step(core::HybridEvaluator& evaluator, core::StepHooks& hooks,
                           core::SimulationResult& result) {
  const std::int64_t k = step_ + 1;
  if (static_cast<std::size_t>(k) >= options_.max_steps)
    refuse("step " + std::to_string(k) + " is beyond the study's motion (" +
           std::to_string(options_.max_steps) + " samples at dt " + std::to_string(options_.dt) +
           " s); give the study a motion as long as the OpenSees analysis");
  const double client_time = trial_[static_cast<std::size_t>(3 * n_)];
  const double advance = client_time - last_time_;
  if (step_ >= 1 && !(std::abs(advance - options_.dt) <= 1e-6 * options_.dt))
    refuse("its time advanced " + std::to_string(advance) + " s from step " +
           std::to_string(step_) + " to " + std::to_string(k) + "; the study's dt is " +
           std::to_string(options_.dt) + " s (the OpenSees analysis must step at the study's dt)");
  hooks.before_step(static_cast<std::size_t>(k));
  step_ = k;
  last_time_ = client_time;
  const auto row = static_cast<Eigen::Index>(k);
  const double t = static_cast<double>(k) * options_.dt;
  mapping_.to_floors(&trial_[0], drift_, u_);
  mapping_.to_floors(&trial_[static_cast<std::size_t>(n_)], drift_, v_);
  mapping_.to_floors(&trial_[static_cast<std::size_t>(2 * n_)], drift_, a_);
  evaluator.set_time(t);
  evaluator.trial(u_, v_, nullptr);
  result.time[static_cast<std::size_t>(k)] = t;
  result.displacement.row(row) = u_.transpose();
  result.velocity.row(row) = v_.transpose();
  result.acceleration.row(row) = a_.transpose();
  result.command.row(row) = evaluator.command().transpose();
  result.realised.row(row) = evaluator.realised().transpose();
  result.measured_force.row(row) = evaluator.measured_force().transpose();
  commanded_ = trial_;
  step_open_ = true;
}

bool Session::get_force(core::HybridEvaluator& evaluator, core::StepHooks& hooks,
                        core::SimulationResult& result) {
  if (have_trial_ && !step_open_) {
    command_step(evaluator, hooks, result);
    const auto k = static_cast<std::size_t>(step_);
    if (!(u_.cwiseAbs().maxCoeff() <= options_.divergence_bound)) {  // also NaN
      result.diverged = true;
      result.truncate(k + 1);
      hooks.after_step(k, result);
      return false;
    }
    if (!hooks.after_step(k, result)) return false;
  } else if (step_open_ && !std::equal(trial_.begin(), trial_.begin() + n_, commanded_.begin())) {
    refuse("getForce at a new displacement inside step " + std::to_string(step_) +
           ", before commitState: the analysis iterates (an implicit integrator or a Newton "
           "algorithm), and an actuator cannot take a displacement back. Use an explicit "
           "integrator (ExplicitDifference, CentralDifference, AlphaOS) with algorithm Linear");
  }
  std::fill(out_.begin(), out_.end(), 0.0);
  if (step_open_) mapping_.to_basic(evaluator.measured_force(), out_.data());
  answer();
  return true;
}

void Session::drive(core::HybridEvaluator& evaluator, core::StepHooks& hooks,
                    core::SimulationResult& result) {
  const auto rows = static_cast<Eigen::Index>(options_.max_steps);
  const int actuators = mapping_.actuators();
  result = core::SimulationResult{};
  result.dt = options_.dt;
  result.time.assign(options_.max_steps, 0.0);
  for (core::Mat* m : {&result.displacement, &result.velocity, &result.acceleration})
    *m = core::Mat::Zero(rows, options_.dofs);
  for (core::Mat* m : {&result.command, &result.realised, &result.measured_force})
    *m = core::Mat::Zero(rows, actuators);
  // Whatever ends the session, the result keeps exactly the steps commanded.
  struct TruncateOnExit {
    core::SimulationResult& result;
    const std::int64_t& step;
    ~TruncateOnExit() { result.truncate(static_cast<std::size_t>(step) + 1); }
  } guard{result, step_};
  if (!hooks.after_step(0, result)) return;
  for (;;) {
    if (!read_frame()) {
      ending_ = "the client closed the connection after step " + std::to_string(step_);
      return;
    }
    Action action{};
    try {
      action = action_of(in_[0]);
    } catch (const ProtocolError& e) {
      refuse(e.what());
    }
    switch (action) {
      case Action::kSetTrialResponse: store_trial(); break;
      case Action::kGetForce:
        if (!get_force(evaluator, hooks, result)) {
          ending_ = result.diverged ? "diverged" : "stopped by the coordinator";
          connection_.end();  // this step's force is never answered
          return;
        }
        break;
      case Action::kCommitState:
        if (step_open_) evaluator.commit();
        step_open_ = false;
        break;
      case Action::kGetInitialStiff:
      case Action::kGetTangentStiff: answer_matrix(&mapping_.stiffness()); break;
      case Action::kGetDamp:
      case Action::kGetMass: answer_matrix(nullptr); break;
      case Action::kDie:
        if (step_open_)
          refuse("ended its element (DIE) inside step " + std::to_string(step_) +
                 ", before committing it");
        ending_ = "the client ended its element (DIE) after step " + std::to_string(step_);
        return;
    }
  }
}

}  // namespace rths::opensees
