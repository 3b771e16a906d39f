#include "view/control_room.h"

#include <sys/random.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>

#include "transport/transport.h"

namespace rths::view {
namespace {

// Equal strings in a time that does not depend on where they differ.
bool same_token(const std::string& a, const std::string& b) {
  unsigned diff = a.size() == b.size() ? 0u : 1u;
  for (std::size_t i = 0; i < a.size() && i < b.size(); ++i)
    diff |= static_cast<unsigned char>(a[i] ^ b[i]);
  return diff == 0 && !a.empty();
}

std::string checked_token(const nlohmann::json& j, const std::string& what) {
  if (!j.is_string())
    throw std::invalid_argument("the view's crew: " + what + "'s token is missing");
  const std::string token = j.get<std::string>();
  if (token.size() < 16)
    throw std::invalid_argument("the view's crew: " + what + "'s token has under 16 characters");
  return token;
}

}  // namespace

std::string make_token() {
  unsigned char bytes[16];
  if (getrandom(bytes, sizeof bytes, 0) != static_cast<ssize_t>(sizeof bytes))
    throw std::runtime_error(std::string("no random bytes for the view's stop token: ") +
                             std::strerror(errno));
  std::string token;
  const char* hex = "0123456789abcdef";
  for (const unsigned byte : bytes) {
    token += hex[byte >> 4];
    token += hex[byte & 0xfu];
  }
  return token;
}

std::string Role::name() const {
  switch (kind) {
    case Kind::kDirector: return "the director";
    case Kind::kOperator: return "the operator of " + lab;
    case Kind::kViewer: break;
  }
  return "a viewer";
}

Crew Crew::make(const std::vector<std::string>& labs) {
  Crew crew{make_token(), make_token(), {}};
  for (const std::string& lab : labs) crew.operators[lab] = make_token();
  return crew;
}

std::optional<Role> Crew::identify(const std::string& token) const {
  // Every token is compared, so the time taken does not tell which role matched.
  std::optional<Role> found;
  if (same_token(token, director)) found = Role{Role::Kind::kDirector, ""};
  if (same_token(token, viewer)) found = Role{Role::Kind::kViewer, ""};
  for (const auto& [lab, lab_token] : operators)
    if (same_token(token, lab_token)) found = Role{Role::Kind::kOperator, lab};
  return found;
}

nlohmann::json Crew::to_json() const {
  return {{"director", director}, {"viewer", viewer}, {"operators", operators}};
}

Crew Crew::from_json(const nlohmann::json& j) {
  Crew crew;
  crew.director = checked_token(j.value("director", nlohmann::json()), "the director");
  crew.viewer = checked_token(j.value("viewer", nlohmann::json()), "the viewer");
  const nlohmann::json operators = j.value("operators", nlohmann::json::object());
  for (const auto& [lab, token] : operators.items())
    crew.operators[lab] = checked_token(token, "the operator of " + lab);
  return crew;
}

std::string Press::text() const {
  std::string t = who + " pressed " + what + " on the view: ";
  if (!allowed) return t + "refused (403), " + why;
  if (stop) return t + "HOLD, then STOP";
  t += "HOLD sent to node";
  t += hold_nodes.size() == 1 ? " " : "s ";
  for (std::size_t i = 0; i < hold_nodes.size(); ++i)
    t += (i ? ", " : "") + std::to_string(hold_nodes[i]);
  return t + "; the run holds until the director stops it";
}

ControlDesk::ControlDesk(Crew crew, std::map<std::string, std::vector<int>> labs)
    : crew_(std::move(crew)), labs_(std::move(labs)) {
  for (const auto& [lab, token] : crew_.operators)
    if (!labs_.count(lab))
      throw std::invalid_argument("the view's crew has an operator of '" + lab +
                                  "', a site with no actuators in this run");
}

Press ControlDesk::judge(const Role& role, const std::string& action,
                         const std::string& lab) const {
  Press p;
  p.who = role.name();
  p.realtime_ns = transport::realtime_ns();
  if (action == "stop") {
    p.what = "STOP";
    p.allowed = role.kind == Role::Kind::kDirector;
    p.stop = p.allowed;
    if (!p.allowed) p.why = "only the director may stop the test";
    return p;
  }
  if (action != "hold") {
    p.what = "'" + action + "'";
    p.why = "not an action of the view (stop or hold)";
    return p;
  }
  p.what = lab.empty() ? "HOLD of every lab" : "HOLD of " + lab;
  const auto found = labs_.find(lab);
  if (!lab.empty() && found == labs_.end()) {
    p.why = "'" + lab + "' is not a lab with actuators in this run";
  } else if (role.kind == Role::Kind::kViewer) {
    p.why = "a viewer may not HOLD";
  } else if (role.kind == Role::Kind::kOperator && lab != role.lab) {
    p.why = role.name() + " may HOLD only " + role.lab + "'s actuators";
  } else {
    p.allowed = true;
    for (const auto& [name, nodes] : labs_)
      if (lab.empty() || name == lab)
        p.hold_nodes.insert(p.hold_nodes.end(), nodes.begin(), nodes.end());
  }
  return p;
}

std::optional<Press> ControlDesk::press(const std::string& token, const std::string& action,
                                        const std::string& lab, std::int64_t seen_step) {
  const std::optional<Role> role = crew_.identify(token);
  if (!role) return std::nullopt;
  Press p = judge(*role, action, lab);
  p.seen_step = seen_step;
  std::lock_guard lock(mutex_);
  queued_.push_back(p);
  pending_.store(true, std::memory_order_relaxed);
  return p;
}

std::vector<Press> ControlDesk::take() {
  std::lock_guard lock(mutex_);
  pending_.store(false, std::memory_order_relaxed);
  return std::exchange(queued_, {});
}

}  // namespace rths::view
