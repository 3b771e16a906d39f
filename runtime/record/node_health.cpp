#include "runtime/record/node_health.h"

#include <fmt/format.h>

#include <algorithm>
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

constexpr int kFramesNamed = 8;  // lost or late frames named in a line; the JSON has them all

nlohmann::json misses_json(const google::protobuf::RepeatedPtrField<FrameMiss>& frames) {
  nlohmann::json out = nlohmann::json::array();
  for (const FrameMiss& m : frames)
    out.push_back({{"frame", m.counter()}, {"step", m.step()}, {"round_trip_s", m.round_trip()}});
  return out;
}

}  // namespace

std::uint64_t controller_rejected(const ControllerReport& r) {
  std::uint64_t n = 0;
  for (const auto& [name, count] : rejects_by_cause(r)) n += count;
  return n;
}

// "12 (step 11), 13 (step 12) and 3 more": frames located by counter and step.
std::string located(const google::protobuf::RepeatedPtrField<FrameMiss>& frames,
                    std::uint64_t total) {
  std::string out;
  const int shown = std::min(frames.size(), kFramesNamed);
  for (int i = 0; i < shown; ++i)
    out += (i ? ", " : "") + std::to_string(frames[i].counter()) + " (step " +
           std::to_string(frames[i].step()) + ")";
  if (total > static_cast<std::uint64_t>(shown))
    out += " and " + std::to_string(total - static_cast<std::uint64_t>(shown)) + " more";
  return out;
}

std::string hold_text(const ControllerReport& r) {
  std::string out = std::to_string(r.hold_frames()) + " HOLD frames";
  if (r.hold_frames() > 0)
    out += r.held_after() >= 0 ? fmt::format(", held after {:.3f} ms", r.held_after() * 1e3)
                               : ", never reported held (stopped after its hold time)";
  if (r.hold_rejected() > 0)
    out += "; " + std::to_string(r.hold_rejected()) +
           " answers while holding did not end the hold (newest: " + r.last_hold_reject() + ")";
  if (!r.restart().empty()) out += "; restart detected: " + r.restart();
  return out;
}

std::string controller_link_text(const NodeRejects& node) {
  if (!node.has_controller()) return "";
  const ControllerReport& r = node.controller();
  std::ostringstream out;
  out << node.label() << " controller link (UDP): " << r.frames_sent() << " frames sent, "
      << r.frames_accepted() << " accepted, " << r.late() << " answered late, " << r.lost()
      << " lost (no answer within the reply timeout); UDP frames rejected: ";
  std::string causes;
  for (const auto& [name, count] : rejects_by_cause(r))
    if (count > 0)
      causes += (causes.empty() ? "" : ", ") + std::string(name) + " " + std::to_string(count);
  out << (causes.empty() ? "none" : causes)
      << fmt::format(
             "; UDP round trip ms: median {:.3f}, p99 {:.3f} (applied answers), max {:.3f} "
             "(every answer); ",
             r.round_trip_median() * 1e3, r.round_trip_p99() * 1e3, r.round_trip_max() * 1e3)
      << hold_text(r);
  if (r.lost() > 0) out << "; lost frames: " << located(r.lost_frames(), r.lost());
  if (r.late() > 0) out << "; late frames: " << located(r.late_frames(), r.late());
  if (r.icmp_errors() > 0)
    out << "; " << r.icmp_errors() << " ICMP errors on the socket, never a fault by themselves ("
        << r.last_icmp_error() << ")";
  if (r.drained_before_connect() > 0)
    out << "; " << r.drained_before_connect()
        << " datagrams that came before the socket was connected, drained unread";
  out << (r.last_reject().empty() ? "" : "; newest: " + r.last_reject()) << "\n";
  return out.str();
}

std::string answer_age_text(const NodeRejects& node) {
  if (!node.has_answer_age() || node.answer_age().steps_judged() == 0) return "";
  const AnswerAge& a = node.answer_age();
  const auto both = [&a](double steps) {
    return fmt::format("{} steps ({:.3f} ms)", static_cast<long long>(steps), steps * a.dt() * 1e3);
  };
  return node.label() + " answer age: median " + both(a.median_steps()) + ", p99 " +
         both(a.p99_steps()) + ", max " + both(a.max_steps()) + "; window " +
         both(a.window_steps()) + "\n";
}

const char* hold_kind_name(HoldEntry::Kind kind) {
  switch (kind) {
    case HoldEntry::SENT_HOLD: return "sent HOLD";
    case HoldEntry::ANSWER: return "answer";
    case HoldEntry::SENT_STOP: return "sent STOP";
    default: return "unknown";
  }
}

nlohmann::json hold_json(const ControllerReport& r) {
  nlohmann::json rows = nlohmann::json::array();
  for (const HoldEntry& e : r.hold_log())
    rows.push_back({{"kind", hold_kind_name(e.kind())},
                    {"time_s", e.time()},
                    {"frame", e.counter()},
                    {"status", e.status()},
                    {"position_m", std::vector<double>(e.position().begin(), e.position().end())},
                    {"force_N", std::vector<double>(e.force().begin(), e.force().end())},
                    {"verdict", e.verdict()}});
  return {{"entries", rows}, {"dropped", r.hold_log_dropped()}};
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
        {"last_reject", r.last_reject()},
        {"hold_rejected", r.hold_rejected()},
        {"last_hold_reject", r.last_hold_reject()},
        {"restart", r.restart()},
        {"icmp_errors", r.icmp_errors()},
        {"last_icmp_error", r.last_icmp_error()},
        {"drained_before_connect", r.drained_before_connect()},
        {"lost_frames", misses_json(r.lost_frames())},
        {"late_frames", misses_json(r.late_frames())},
        {"hold", hold_json(r)}};
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
