#include "tests/support/doc_controller.h"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <bit>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstring>
#include <limits>
#include <stdexcept>

namespace rths::test {
namespace {

std::int64_t now_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

// Big-endian (network order) packing, as LabVIEW's Flatten To String writes it.
void put_u32(std::vector<std::uint8_t>& out, std::uint32_t v) {
  out.push_back(static_cast<std::uint8_t>(v >> 24));
  out.push_back(static_cast<std::uint8_t>(v >> 16));
  out.push_back(static_cast<std::uint8_t>(v >> 8));
  out.push_back(static_cast<std::uint8_t>(v));
}
void put_f32(std::vector<std::uint8_t>& out, float v) {
  put_u32(out, std::bit_cast<std::uint32_t>(v));
}
std::uint32_t get_u32(const std::uint8_t* p) {
  return (std::uint32_t{p[0]} << 24) | (std::uint32_t{p[1]} << 16) | (std::uint32_t{p[2]} << 8) |
         std::uint32_t{p[3]};
}
float get_f32(const std::uint8_t* p) { return std::bit_cast<float>(get_u32(p)); }

sockaddr_in loopback(int port) {
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(static_cast<std::uint16_t>(port));
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  return a;
}

}  // namespace

std::string to_string(DocFault fault) {
  switch (fault) {
    case DocFault::kNone: return "none";
    case DocFault::kSilent: return "silent";
    case DocFault::kBadStatus: return "bad status";
    case DocFault::kNanForce: return "NaN force";
    case DocFault::kWrongEcho: return "wrong echo";
    case DocFault::kWrongSize: return "wrong size";
    case DocFault::kOutOfRange: return "out of range";
    case DocFault::kCounterReset: return "counter reset";
    case DocFault::kReboot: return "reboot";
    case DocFault::kForceJump: return "force jump";
    case DocFault::kStuckDisplacement: return "stuck displacement";
  }
  return "?";
}

std::string doc_controller_link_text(int node_port, int peer_port, const std::string& extra) {
  const std::string big = " byte_order: ORDER_BIG";
  return "local_address: \"127.0.0.1\" local_port: " + std::to_string(node_port) +
         " peer_address: \"127.0.0.1\" peer_port: " + std::to_string(peer_port) +
         " command { fields { name: \"counter\" role: COUNTER type: U32" + big +
         " } fields { name: \"spare\" role: PADDING type: U32" + big +
         " } fields { name: \"status\" role: STATUS type: I32" + big +
         " } fields { name: \"target\" role: TARGET_DISPLACEMENT type: F32" + big +
         " scale: 0.001 unit: \"mm\" } fields { name: \"spare2\" role: PADDING type: F32" + big +
         " } } feedback { fields { name: \"echo\" role: COUNTER type: U32" + big +
         " } fields { name: \"status\" role: STATUS type: I32" + big +
         " } fields { name: \"spare\" role: PADDING type: U32" + big +
         " } fields { name: \"displacement\" role: MEASURED_DISPLACEMENT type: F32" + big +
         " scale: 0.001 unit: \"mm\" } fields { name: \"force\" role: MEASURED_FORCE type: F32" +
         big + " scale: 1000 unit: \"kN\" } fields { name: \"spare2\" role: PADDING type: F32" +
         big + " } } " + extra;
}

double through_f32(double si, double scale) {
  return static_cast<double>(static_cast<float>(si / scale)) * scale;
}

DocController::DocController(const DocControllerOptions& options) : options_(options) {
  socket_ = ::socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  if (socket_ < 0)
    throw std::runtime_error("doc controller: socket: " + std::string(strerror(errno)));
  const int one = 1;
  ::setsockopt(socket_, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
  const sockaddr_in local = loopback(options_.port);
  if (::bind(socket_, reinterpret_cast<const sockaddr*>(&local), sizeof local) != 0) {
    const std::string why = strerror(errno);
    ::close(socket_);
    throw std::runtime_error("doc controller: bind 127.0.0.1:" + std::to_string(options_.port) +
                             ": " + why);
  }
  receiver_ = std::thread([this] { receive_loop(); });
  sender_ = std::thread([this] { send_loop(); });
}

DocController::~DocController() { stop(); }

void DocController::stop() {
  if (!running_.exchange(false)) return;
  queue_cv_.notify_all();
  if (receiver_.joinable()) receiver_.join();
  if (sender_.joinable()) sender_.join();
  ::close(socket_);
}

std::vector<ReceivedFrame> DocController::received() const {
  std::lock_guard lock(log_mutex_);
  return received_;
}

std::vector<SentAnswer> DocController::sent() const {
  std::lock_guard lock(log_mutex_);
  return sent_;
}

void DocController::receive_loop() {
  std::vector<std::uint8_t> buffer(65536);
  while (running_) {
    pollfd p{socket_, POLLIN, 0};
    if (::poll(&p, 1, 20) <= 0) continue;
    const ssize_t n = ::recv(socket_, buffer.data(), buffer.size(), 0);
    if (n < 0) continue;
    ReceivedFrame frame;
    frame.receive_ns = now_ns();
    frame.bytes = static_cast<std::size_t>(n);
    // A frame of another size is not a command frame: logged, never acted on (as the byte-count
    // check of the docs' LabVIEW recipe).
    if (frame.bytes == kDocCommandBytes) {
      const std::uint8_t* b = buffer.data();
      frame.counter = get_u32(b);
      frame.padding_zero = get_u32(b + 4) == 0 && get_u32(b + 16) == 0;
      frame.status = static_cast<std::int32_t>(get_u32(b + 8));
      frame.target = static_cast<double>(get_f32(b + 12)) * kMm;
    }
    {
      std::lock_guard lock(log_mutex_);
      received_.push_back(frame);
    }
    if (frame.bytes != kDocCommandBytes) continue;
    Pending pending;
    if (!answer_for(frame, pending.answer, pending.bytes)) continue;
    pending.due_ns = frame.receive_ns + static_cast<std::int64_t>(options_.answer_lag * 1e9);
    if (options_.answer_lag <= 0) {
      send_now(pending);
    } else {
      std::lock_guard lock(queue_mutex_);
      queue_.push_back(std::move(pending));
      queue_cv_.notify_all();
    }
  }
}

void DocController::send_loop() {
  std::unique_lock lock(queue_mutex_);
  while (running_) {
    if (queue_.empty()) {
      queue_cv_.wait_for(lock, std::chrono::milliseconds(20));
      continue;
    }
    // Answers are due in arrival order (one lag for all): the front is the next to leave.
    const std::int64_t due = queue_.front().due_ns;
    if (now_ns() < due) {
      queue_cv_.wait_until(lock,
                           std::chrono::steady_clock::time_point(std::chrono::nanoseconds(due)));
      continue;
    }
    Pending pending = std::move(queue_.front());
    queue_.pop_front();
    lock.unlock();
    send_now(pending);
    lock.lock();
  }
}

void DocController::send_now(Pending& pending) {
  const sockaddr_in to = loopback(options_.node_port);
  pending.answer.send_ns = now_ns();
  ::sendto(socket_, pending.bytes.data(), pending.bytes.size(), 0,
           reinterpret_cast<const sockaddr*>(&to), sizeof to);
  std::lock_guard lock(log_mutex_);
  sent_.push_back(pending.answer);
}

bool DocController::answer_for(const ReceivedFrame& frame, SentAnswer& answer,
                               std::vector<std::uint8_t>& out) {
  if (stopped_ || silent_) return false;
  if (frame.status == 2) {  // the rig's own stop: nothing answered from now on
    stopped_ = true;
    return false;
  }
  const bool run = frame.status == 0;
  const bool faulted = options_.fault != DocFault::kNone && frame.counter >= options_.fault_frame;
  if (faulted && options_.fault == DocFault::kSilent) {
    silent_ = true;
    return false;
  }
  std::int32_t status = 0;
  if (run) {
    if (faulted && options_.fault == DocFault::kStuckDisplacement && !stuck_) {
      stuck_ = true;
      stuck_at_ = measured_;
    }
    if (faulted && options_.fault == DocFault::kReboot && !rebooted_) {
      rebooted_ = true;  // the controller restarted: its state is gone, its plant at rest at 0
      history_.clear();
      measured_ = 0.0;
    } else if (options_.first_order_tau > 0) {
      measured_ +=
          (1.0 - std::exp(-options_.dt / options_.first_order_tau)) * (frame.target - measured_);
    } else {
      const auto lag_frames =
          static_cast<std::size_t>(std::lround(options_.pure_lag / options_.dt));
      history_.push_back(frame.target);
      if (history_.size() > lag_frames) {
        measured_ = history_.front();
        history_.pop_front();
      } else {
        measured_ = 0.0;
      }
    }
  } else {
    // HOLD: take the frame's target, the position to hold, and stay there.
    measured_ = frame.target;
    history_.clear();
    ++hold_frames_;
    const int need = options_.held_after_hold_frames;
    status = need >= 0 && hold_frames_ >= need ? 1 : 0;
  }
  double displacement = measured_;
  std::uint32_t echo = frame.counter;
  bool longer = false;
  const bool corrupt = run && faulted;
  if (corrupt) {
    switch (options_.fault) {
      case DocFault::kBadStatus: status = static_cast<std::int32_t>(options_.fault_value); break;
      case DocFault::kWrongEcho: echo = frame.counter + 100000; break;
      case DocFault::kWrongSize: longer = true; break;
      case DocFault::kOutOfRange: displacement = options_.fault_value; break;
      case DocFault::kCounterReset: echo = frame.counter - options_.fault_frame + 1; break;
      case DocFault::kStuckDisplacement: displacement = stuck_at_; break;
      default: break;
    }
  }
  double force = options_.stiffness * displacement;
  if (corrupt && options_.fault == DocFault::kNanForce)
    force = std::numeric_limits<double>::quiet_NaN();
  if (corrupt && options_.fault == DocFault::kForceJump) force += options_.fault_value;

  const auto mm = static_cast<float>(displacement / kMm);
  const auto kn = static_cast<float>(force / kKn);
  out.clear();
  put_u32(out, echo);
  put_u32(out, static_cast<std::uint32_t>(status));
  put_u32(out, 0xDEADBEEFu);  // padding: never read
  put_f32(out, mm);
  put_f32(out, kn);
  put_f32(out, options_.f32_padding);  // padding: never judged finite
  if (longer) put_u32(out, 0);

  answer.counter = frame.counter;
  answer.echo = echo;
  answer.status = status;
  answer.displacement = static_cast<double>(mm) * kMm;
  answer.force = static_cast<double>(kn) * kKn;
  answer.faulty = corrupt && options_.fault != DocFault::kNone;
  return true;
}

}  // namespace rths::test
