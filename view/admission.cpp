#include "view/admission.h"

#include <algorithm>

namespace rths::view {

Admission::Admission(AdmissionLimits limits) : limits_(limits) {
  // At least one of each: a full table always has a candidate to displace.
  limits_.max_waiting = std::max<std::size_t>(limits_.max_waiting, 1);
  limits_.max_per_address =
      std::clamp<std::size_t>(limits_.max_per_address, 1, limits_.max_waiting);
}

bool Admission::idler(const Waiting& a, const Waiting& b) {
  if ((a.bytes == 0) != (b.bytes == 0)) return a.bytes == 0;
  return a.active < b.active;
}

std::size_t Admission::from(std::uint32_t address) const {
  return static_cast<std::size_t>(std::count_if(
      waiting_.begin(), waiting_.end(), [&](const Waiting& w) { return w.address == address; }));
}

std::optional<int> Admission::displaced_by(std::uint32_t address) const {
  const bool at_address_limit = from(address) >= limits_.max_per_address;
  if (!at_address_limit && waiting_.size() < limits_.max_waiting) return std::nullopt;
  const Waiting* chosen = nullptr;  // never null after the loop: the limits are at least 1
  for (const Waiting& w : waiting_) {
    if (at_address_limit && w.address != address) continue;
    if (chosen == nullptr || idler(w, *chosen)) chosen = &w;
  }
  return chosen->fd;
}

void Admission::add(int fd, std::uint32_t address, Clock::time_point now) {
  waiting_.push_back({fd, address, now, now, 0});
  at_[fd] = std::prev(waiting_.end());
}

bool Admission::saw_bytes(int fd, std::size_t bytes, Clock::time_point now) {
  const auto at = at_.find(fd);
  if (at == at_.end() || bytes <= at->second->bytes) return false;
  at->second->bytes = bytes;
  at->second->active = now;
  return true;
}

bool Admission::remove(int fd) {
  const auto at = at_.find(fd);
  if (at == at_.end()) return false;
  waiting_.erase(at->second);
  at_.erase(at);
  return true;
}

std::vector<int> Admission::take_arrived_by(Clock::time_point cutoff) {
  std::vector<int> taken;
  while (!waiting_.empty() && waiting_.front().arrived <= cutoff) {
    taken.push_back(waiting_.front().fd);
    at_.erase(waiting_.front().fd);
    waiting_.pop_front();
  }
  return taken;
}

std::vector<int> Admission::fds() const {
  std::vector<int> out;
  out.reserve(waiting_.size());
  for (const Waiting& w : waiting_) out.push_back(w.fd);
  return out;
}

}  // namespace rths::view
