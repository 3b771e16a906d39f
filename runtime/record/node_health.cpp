#include "runtime/record/node_health.h"

#include <sstream>
#include <utility>
#include <vector>

namespace rths::runtime {
namespace {

std::vector<std::pair<const char*, std::uint64_t>> rejects_by_cause(const ControllerReport& r) {
  return {{"wrong source", r.wrong_source()},
          {"wrong size", r.wrong_size()},
          {"repeated counter", r.repeated_counter()},
          {"unexpected counter", r.unexpected_counter()},
          {"not finite", r.non_finite()},
          {"out of range", r.out_of_range()},
          {"bad status", r.bad_status()},
          {"implausible", r.implausible()}};
}

std::string ms(double seconds) {
  std::ostringstream out;
  out.precision(3);
  out << std::fixed << seconds * 1e3;
  return out.str();
}

}  // namespace

std::uint64_t controller_rejected(const ControllerReport& r) {
  std::uint64_t n = 0;
  for (const auto& [name, count] : rejects_by_cause(r)) n += count;
  return n;
}

std::string controller_link_text(const NodeRejects& node) {
  if (!node.has_controller()) return "";
  const ControllerReport& r = node.controller();
  std::ostringstream out;
  out << node.label() << " controller link: " << r.frames_sent() << " frames sent, "
      << r.frames_accepted() << " accepted, " << r.late() << " late, " << r.lost()
      << " lost; rejected: ";
  std::string causes;
  for (const auto& [name, count] : rejects_by_cause(r))
    if (count > 0)
      causes += (causes.empty() ? "" : ", ") + std::string(name) + " " + std::to_string(count);
  out << (causes.empty() ? "none" : causes) << "; UDP round trip ms: median "
      << ms(r.round_trip_median()) << ", p99 " << ms(r.round_trip_p99()) << ", max "
      << ms(r.round_trip_max()) << "; " << r.hold_frames() << " HOLD frames"
      << (r.hold_frames() == 0  ? ""
          : r.held_after() >= 0 ? ", held after " + ms(r.held_after()) + " ms"
                                : ", never reported held (stopped after its hold time)")
      << (r.last_reject().empty() ? "" : "; newest: " + r.last_reject()) << "\n";
  return out.str();
}

std::string answer_age_text(const NodeRejects& node) {
  if (!node.has_answer_age() || node.answer_age().steps_judged() == 0) return "";
  const AnswerAge& a = node.answer_age();
  const auto both = [&a](double steps) {
    return std::to_string(static_cast<long long>(steps)) + " steps (" + ms(steps * a.dt()) + " ms)";
  };
  return node.label() + " answer age: median " + both(a.median_steps()) + ", p99 " +
         both(a.p99_steps()) + ", max " + both(a.max_steps()) + "; window " +
         both(a.window_steps()) + "\n";
}

nlohmann::json node_health_json(const NodeRejects& node) {
  nlohmann::json j;
  if (node.has_controller()) {
    const ControllerReport& r = node.controller();
    nlohmann::json rejected = nlohmann::json::object();
    for (const auto& [name, count] : rejects_by_cause(r)) rejected[name] = count;
    j["controller"] = {
        {"frames_sent", r.frames_sent()},
        {"frames_accepted", r.frames_accepted()},
        {"late", r.late()},
        {"lost", r.lost()},
        {"rejected", rejected},
        {"rejected_total", controller_rejected(r)},
        {"round_trip_median_s", r.round_trip_median()},
        {"round_trip_p99_s", r.round_trip_p99()},
        {"round_trip_max_s", r.round_trip_max()},
        {"hold_frames", r.hold_frames()},
        {"held_after_s", r.held_after() >= 0 ? nlohmann::json(r.held_after()) : nlohmann::json()},
        {"last_reject", r.last_reject()}};
  } else {
    j["controller"] = nullptr;
  }
  if (node.has_answer_age() && node.answer_age().steps_judged() > 0) {
    const AnswerAge& a = node.answer_age();
    j["answer_age"] = {{"steps_judged", a.steps_judged()},
                       {"median_steps", a.median_steps()},
                       {"p99_steps", a.p99_steps()},
                       {"max_steps", a.max_steps()},
                       {"window_steps", a.window_steps()},
                       {"median_ms", a.median_steps() * a.dt() * 1e3},
                       {"p99_ms", a.p99_steps() * a.dt() * 1e3},
                       {"max_ms", a.max_steps() * a.dt() * 1e3}};
  } else {
    j["answer_age"] = nullptr;
  }
  return j;
}

std::optional<std::string> link_verdict(const NodeRejects& node) {
  if (!node.has_controller()) return std::nullopt;
  const ControllerReport& r = node.controller();
  const std::uint64_t rejected = controller_rejected(r);
  if (r.lost() == 0 && r.late() == 0 && rejected == 0) return std::nullopt;
  std::string why = node.label() + "'s controller link was not clean: " + std::to_string(r.lost()) +
                    " frames lost, " + std::to_string(r.late()) + " answered late, " +
                    std::to_string(rejected) + " rejected";
  if (r.wrong_source() > 0)
    why += " (" + std::to_string(r.wrong_source()) +
           " from a wrong source: someone else sends "
           "on the controller's network)";
  return why;
}

}  // namespace rths::runtime
