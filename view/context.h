#pragma once
// Facts about a run the record does not hold, for the view:
//   run_context   the case's critical-delay check (analysis::check_case_critical_delay, the check
//                 `rths run` and `rths launch` make before a case runs): {"critical_delay":
//                 {"lag_ms", "critical_delay_ms", "margin_pct", "text"}}, or {"text": why not}
//                 when the structure has no experimental part or the study cannot be prepared;
//                 "node_kinds": {"<node id>": "SUBSTRUCTURE" | "ACTUATOR_EMULATOR" | ...} of the
//                 deployment (its default nodes when it declares none), to label the links;
//                 and link_context's facts.
//   predict_case  the in-process prediction: core::simulate of the case's in-process setup
//                 (runtime::in_process_setup: its delay stages and compensation, the emulators'
//                 compensation), the response `rths run` computes for the case, keeping the
//                 DOFs the study's recorders keep (prepared.recorders.kept_dofs: the record's
//                 columns; empty: every DOF), so a large model's prediction is O(recorded) a
//                 step as its record is. A lockstep run without node delay stages equals it bit
//                 for bit; the links' lag and the nodes' own delay stages are not in it, so in
//                 real time the measured response differs from it by what they (and the
//                 actuator) did.
//   describe_run  both into a Feed: its context (run_context plus "prediction": {"text", "steps",
//                 "diverged"} or {"text": why there is none}) and its prediction. Called before
//                 the run starts (the coordinator) or on the view's side (`rths view`), never on
//                 the loop thread: the prediction runs the whole case.

#include <filesystem>
#include <string>

#include <nlohmann/json.hpp>

#include "core/simulation.h"
#include "runtime/record/record.h"
#include "study/study.h"
#include "view/feed.h"

namespace rths::view {

nlohmann::json run_context(const study::PreparedStudy& prepared, const std::string& case_name);
// What the control room shows per link, in run_context: "critical_round_trip" {"ms": the round
// trip a link may add before the loop is unstable, "label": compensated (a force predictor as it
// starts, analysis::predicted_loop_verdict, where it finds the loop stable; "unbounded": true
// and no "ms" when stable for every round trip) or uncompensated (the critical delay less the
// case's own lag), "text"}; "answer_window_steps" (runtime::max_missed_answers: an older answer stops
// the run); "node_actuators" {"<node id>": [actuator indices]}.
nlohmann::json link_context(const study::PreparedStudy& prepared, const std::string& case_name);

// Throws std::invalid_argument naming the case or the block that cannot be built.
core::SimulationResult predict_case(const study::PreparedStudy& prepared,
                                    const std::string& case_name);

// `note` (e.g. a cut record's warning), when not empty, is shown as context["note"].
void describe_run(Feed& feed, const study::PreparedStudy& prepared, const std::string& case_name,
                  const std::string& note = "");
// The motion a record's steps carry: their ground acceleration (m/s^2) at the header's dt, over
// the steps 0, 1, ... up to the first one missing.
core::GroundMotion recorded_motion(const runtime::RecordContents& contents);
// describe_run for a record (`rths view`), its header required: the study prepared from the
// header with `base_dir` resolving its relative paths. When the study's motion file cannot be
// read here (a record carried away from the lab), the record's own motion (recorded_motion)
// stands in, so the prediction covers the recorded steps (and the record's recorded DOFs) and
// the page says so; when the study cannot be set up at all, the context says why. The record's
// warning (cut short, damaged) is the note. A real-time record that overran gets its deadline diagnosis
// (runtime::diagnose_record_deadlines, the lines `rths launch` prints) beneath its badge.
void describe_record(Feed& feed, const runtime::RecordContents& contents,
                     const std::filesystem::path& base_dir);

}  // namespace rths::view
