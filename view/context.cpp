#include "view/context.h"

#include "analysis/study_run/study_run.h"
#include "runtime/node/in_process.h"
#include "runtime/node/plan.h"
#include "runtime/record/deadline_diagnosis.h"
#include "study/study_inputs.h"

namespace rths::view {

namespace {

// The round trip a link may add before the loop goes unstable: the compensated loop's (a force
// predictor as it starts, analysis::predicted_loop_verdict) where it is analysed, else the
// uncompensated critical delay less the case's own lag (analysis::check_case_critical_delay);
// "label" says which, "text" why there is none.
nlohmann::json critical_round_trip(const study::PreparedStudy& prepared,
                                   const config::Case& study_case) {
  const auto compensated = analysis::predicted_loop_verdict(prepared, study_case, 0.0);
  if (compensated && compensated->analysed && compensated->stable) {
    nlohmann::json j = {{"label", "compensated (force predictor as it starts)"},
                        {"text", compensated->text}};
    if (compensated->extra_delay_tolerated)
      j["ms"] = *compensated->extra_delay_tolerated * 1e3;
    else
      j["unbounded"] = true;  // stable for every round trip
    return j;
  }
  const auto check = analysis::check_case_critical_delay(prepared, study_case);
  nlohmann::json j = {{"text", check ? check->describe() : "no experimental part"}};
  if (compensated) j["compensated_text"] = compensated->text;
  if (check && check->critical()) {
    j["ms"] = (*check->critical() - check->lag) * 1e3;
    j["label"] =
        compensated ? "uncompensated (the compensated loop is not analysed here)" : "uncompensated";
  }
  return j;
}

}  // namespace

nlohmann::json link_context(const study::PreparedStudy& prepared, const std::string& case_name) {
  nlohmann::json j;
  try {
    j["critical_round_trip"] =
        critical_round_trip(prepared, study::find_case(prepared.config, case_name));
  } catch (const std::exception& e) {
    j["critical_round_trip"] = {{"text", std::string("not known: ") + e.what()}};
  }
  const config::Deployment deployment =
      runtime::with_default_nodes(prepared.config.deployment(), prepared.base);
  j["answer_window_steps"] = runtime::max_missed_answers(deployment, prepared.base.dt);
  try {
    for (const runtime::NodePlan& node : runtime::make_plan(prepared.base, deployment).nodes)
      j["node_actuators"][std::to_string(node.spec.id())] = node.actuators;
  } catch (const std::exception&) {  // a plan the run refuses has no actuators to show
  }
  return j;
}

nlohmann::json run_context(const study::PreparedStudy& prepared, const std::string& case_name) {
  nlohmann::json critical;
  try {
    const config::Case& study_case = study::find_case(prepared.config, case_name);
    const auto check = analysis::check_case_critical_delay(prepared, study_case);
    if (!check || !check->critical()) {
      critical["text"] =
          check ? "stable for every delay" : "no experimental part: no critical delay";
    } else {
      critical = {{"lag_ms", check->lag * 1e3},
                  {"critical_delay_ms", *check->critical() * 1e3},
                  {"margin_pct", check->margin() * 100.0},
                  {"text", check->describe()}};
    }
  } catch (const std::exception& e) {
    critical["text"] = std::string("not known: ") + e.what();
  }
  nlohmann::json context = link_context(prepared, case_name);
  context["critical_delay"] = critical;
  // The node behind each link: the deployment's default nodes when it declares none.
  const config::Deployment deployment =
      runtime::with_default_nodes(prepared.config.deployment(), prepared.base);
  for (const config::NodeSpec& node : deployment.nodes())
    context["node_kinds"][std::to_string(node.id())] = config::NodeSpec::Kind_Name(node.kind());
  return context;
}

core::SimulationResult predict_case(const study::PreparedStudy& prepared,
                                    const std::string& case_name) {
  const config::Case& study_case = study::find_case(prepared.config, case_name);
  core::SimulationOptions recorded;  // the record's columns: what the recorders keep
  recorded.kept_dofs = prepared.recorders.kept_dofs;
  return core::simulate(runtime::in_process_setup(prepared, study_case), prepared.motion, recorded);
}

namespace {

// `motion_text`, when not empty, says where the motion came from (in the prediction's text).
void describe(Feed& feed, const study::PreparedStudy& prepared, const std::string& case_name,
              const std::string& note, const std::string& motion_text) {
  nlohmann::json context = run_context(prepared, case_name);
  try {
    const core::SimulationResult prediction = predict_case(prepared, case_name);
    feed.set_prediction(prediction);
    const std::string name = study::find_case(prepared.config, case_name).name();
    context["prediction"] = {{"text", "in-process run of case " + name +
                                          " (its delays and compensation; not the links' lag)" +
                                          motion_text + (prediction.diverged ? ": diverged" : "")},
                             {"steps", prediction.steps()},
                             {"diverged", prediction.diverged}};
  } catch (const std::exception& e) {
    context["prediction"] = {{"text", std::string("no in-process prediction: ") + e.what()}};
  }
  if (!note.empty()) context["note"] = note;
  feed.set_context(std::move(context));
}

}  // namespace

void describe_run(Feed& feed, const study::PreparedStudy& prepared, const std::string& case_name,
                  const std::string& note) {
  describe(feed, prepared, case_name, note, "");
}

core::GroundMotion recorded_motion(const runtime::RecordContents& contents) {
  core::GroundMotion motion;
  motion.name = "the record's steps";
  motion.dt = contents.header() ? contents.header()->dt() : 0.0;
  for (const runtime::StepRecord* step : contents.steps()) {
    if (step->step() != static_cast<std::int64_t>(motion.acceleration.size())) break;
    motion.acceleration.push_back(step->ground_acceleration());
  }
  return motion;
}

namespace {

// The context of a record from its study: prepared here, else over the record's own motion, else
// the reason neither could be.
void describe_record_study(Feed& feed, const runtime::RecordContents& contents,
                           const std::filesystem::path& base_dir) {
  const runtime::RunHeader& header = *contents.header();
  const config::Study& study = *contents.study_as_run();
  const std::string note = contents.warning;
  std::string why;
  try {
    describe(feed, study::prepare_study(study, base_dir), header.case_name(), note,
             ", inputs " + study::inputs_source(study, base_dir));
    return;
  } catch (const std::exception& e) {
    why = e.what();
  }
  try {  // the study's motion file is not here: the record's steps carry the motion
    study::PreparedStudy prepared;
    prepared.config = study;
    prepared.base_dir = base_dir;
    prepared.motion = recorded_motion(contents);
    if (prepared.motion.acceleration.size() < 2)
      throw std::invalid_argument("the record has too few steps to carry the motion");
    prepared.base = study::base_setup(study, header.dt(), base_dir);
    // The DOFs the record holds (none named: every DOF), as its recorders kept them.
    prepared.recorders.kept_dofs.assign(header.recorded_dofs().begin(),
                                        header.recorded_dofs().end());
    describe(feed, prepared, header.case_name(), note,
             ", over the motion of the record's " +
                 std::to_string(prepared.motion.acceleration.size()) + " steps (" + why + ")");
  } catch (const std::exception& e) {
    const std::string text = std::string("not known: ") + why + "; " + e.what();
    nlohmann::json context = {{"critical_delay", {{"text", text}}},
                              {"prediction", {{"text", "no in-process prediction: " + text}}}};
    if (!note.empty()) context["note"] = note;
    feed.set_context(std::move(context));
  }
}

}  // namespace

void describe_record(Feed& feed, const runtime::RecordContents& contents,
                     const std::filesystem::path& base_dir) {
  describe_record_study(feed, contents, base_dir);
  const auto deadlines = runtime::diagnose_record_deadlines(contents);
  if (deadlines && deadlines->overruns > 0) feed.set_deadline_diagnosis(deadlines->describe());
}

}  // namespace rths::view
