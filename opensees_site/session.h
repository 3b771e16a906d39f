#pragma once
// One OpenSees client's analysis, served as the coordinator's integrator (a
// coordinator::StepDriver): the element's trials become the coordinator's steps.
//
// Frames (opensees_site/protocol.h) and what each does:
//   3  setTrialResponse  stores the trial (basic disp, vel, accel; time). Nothing moves yet.
//   10 getForce          the first in a step commands the newest trial: step k = k + 1,
//                        hooks.before_step(k) (real time: deadline k), evaluator.set_time(k dt),
//                        evaluator.trial(u, v) with u, v the floors of T u_b, T v_b; row k of
//                        the result; hooks.after_step(k); answers f_b = T^T f_measured. A later
//                        getForce in the same step at the same displacement gets the same force.
//   5  commitState       evaluator.commit(); the step is closed (the next getForce opens one).
//   12/13                K_b (mapping.h); 14 / 15 zeros (damping and mass are the model's).
//   99, or a close between steps: the analysis is over; drive() returns.
// So OpenSees' explicit integrators map one analysis step to one command, whatever their order
// (3, 14, 10, 5; ExplicitDifference 3, 10, 14, 3, 5; CentralDifference asks the force at the
// displacement its previous step set).
// Refused (coordinator::RunAborted: the coordinator holds the actuators, stops the nodes and
// closes the record with the reason, which names the problem):
//   a getForce at a displacement other than the one already commanded in the step (an implicit
//   integrator's or a Newton algorithm's iteration: an actuator cannot take a displacement back);
//   a non-finite trial; an unknown action; a truncated frame; nothing from the client within
//   the frame timeout (real time: the emulator's watchdog, command_watchdog_periods x dt;
//   lockstep: step_timeout); a client time step other than dt; more steps than the motion has;
//   a close inside a step.
// Real-time safety: frames, trial and answer buffers are sized once; a step allocates nothing.

#include <chrono>
#include <cstdint>
#include <string>
#include <vector>

#include "core/simulation.h"
#include "opensees_site/mapping.h"
#include "opensees_site/protocol.h"
#include "opensees_site/tcp_channel.h"

namespace rths::opensees {

struct SessionOptions {
  double dt = 0.0;            // s, the study's step
  std::size_t max_steps = 0;  // rows of the result: the motion's samples
  int dofs = 0;               // the study's floors
  int frame_size = kDefaultFrameSize;
  // Before the first command (the analysis may still be setting up) and between frames after it.
  std::chrono::nanoseconds first_frame_timeout{std::chrono::seconds(10)};
  std::chrono::nanoseconds frame_timeout{std::chrono::seconds(2)};
  std::string frame_timeout_reason;  // what the limit is, for the message
  double divergence_bound = 1.0e3;   // m
  std::string client;  // label of the client in messages ("OpenSees client 127.0.0.1:5")
};

class Session {
 public:
  Session(Connection& connection, const BasicMapping& mapping, SessionOptions options);
  // The coordinator::StepDriver contract (coordinator.h). Returns when the client is done.
  void drive(core::HybridEvaluator& evaluator, core::StepHooks& hooks,
             core::SimulationResult& result);
  // How the analysis ended ("DIE after step 1500"), once drive() returned.
  const std::string& ending() const { return ending_; }
  std::int64_t steps() const { return step_; }

 private:
  // Reads the next frame into in_; false when the client closed between frames.
  bool read_frame();
  void store_trial();
  // getForce: commands a new step when the step has none yet; answers the force.
  bool get_force(core::HybridEvaluator& evaluator, core::StepHooks& hooks,
                 core::SimulationResult& result);
  void command_step(core::HybridEvaluator& evaluator, core::StepHooks& hooks,
                    core::SimulationResult& result);
  void answer_matrix(const core::Mat* matrix);
  void answer();
  [[noreturn]] void refuse(const std::string& why) const;

  Connection& connection_;
  const BasicMapping& mapping_;
  SessionOptions options_;
  const int n_;
  std::vector<double> in_, out_;
  std::vector<double> trial_, commanded_;  // basic disp, vel, accel, time (3n + 1)
  bool have_trial_ = false, step_open_ = false;
  std::int64_t step_ = 0;
  double last_time_ = 0.0;
  core::Vec drift_, u_, v_, a_;
  std::string ending_;
};

}  // namespace rths::opensees
