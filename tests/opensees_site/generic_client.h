#pragma once
// A stand-in for OpenSees' genericClient element, byte for byte as GenericClient.cpp and
// TCP_Socket.cpp send: it connects, sends 11 native ints (sizes, [10] = the frame size), then
// frames of frame_size native doubles, the action in slot 0, and reads frame_size doubles back
// after the actions that expect an answer. Also the one-storey frame's explicit analysis that
// an OpenSees model of the example (examples/opensees/) runs, with its column either served
// (basic DOFs: node 1 DOF 1, node 2 DOF 1) or an elastic element of the same stiffness.

#include <arpa/inet.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <sys/socket.h>
#include <unistd.h>

#include <array>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

namespace rths::test {

class GenericClient {
 public:
  GenericClient(int port, int basic_dofs, int frame_size = 256)
      : n_(basic_dofs), frame_(frame_size) {
    fd_ = ::socket(AF_INET, SOCK_STREAM, 0);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_port = htons(static_cast<std::uint16_t>(port));
    a.sin_addr.s_addr = inet_addr("127.0.0.1");
    if (::connect(fd_, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0)
      throw std::runtime_error("cannot connect to 127.0.0.1:" + std::to_string(port));
    int zero = 0;  // TCP_Socket's noDelay default
    ::setsockopt(fd_, IPPROTO_TCP, TCP_NODELAY, &zero, sizeof zero);
  }
  ~GenericClient() { close(); }
  GenericClient(const GenericClient&) = delete;
  GenericClient& operator=(const GenericClient&) = delete;

  // genericClient's setupConnection(): disp, vel, accel sizes n, time size 1, force size n.
  std::array<std::int32_t, 11> sizes() const {
    std::array<std::int32_t, 11> s{};
    s[0] = s[1] = s[2] = s[8] = n_;
    s[4] = 1;
    s[10] = frame_;
    return s;
  }
  void send_sizes() { send_sizes(sizes()); }
  void send_sizes(const std::array<std::int32_t, 11>& s) { send_bytes(s.data(), sizeof s); }

  void set_trial(const std::vector<double>& disp, const std::vector<double>& vel,
                 const std::vector<double>& accel, double time) {
    std::vector<double> f(static_cast<std::size_t>(frame_), 0.0);
    f[0] = 3;
    for (int i = 0; i < n_; ++i) {
      f[static_cast<std::size_t>(1 + i)] = disp[static_cast<std::size_t>(i)];
      f[static_cast<std::size_t>(1 + n_ + i)] = vel[static_cast<std::size_t>(i)];
      f[static_cast<std::size_t>(1 + 2 * n_ + i)] = accel[static_cast<std::size_t>(i)];
    }
    f[static_cast<std::size_t>(1 + 3 * n_)] = time;
    send_frame(f);
  }
  // Actions that expect an answer: the answer frame.
  std::vector<double> ask(int action) {
    send_action(action);
    std::vector<double> answer(static_cast<std::size_t>(frame_));
    if (!recv_bytes(answer.data(), answer.size() * sizeof(double)))
      throw std::runtime_error("the server closed the connection instead of answering action " +
                               std::to_string(action));
    return answer;
  }
  void send_action(int action) {
    std::vector<double> f(static_cast<std::size_t>(frame_), 0.0);
    f[0] = action;
    send_frame(f);
  }
  void send_frame(const std::vector<double>& f) { send_bytes(f.data(), f.size() * sizeof(double)); }
  void send_bytes(const void* data, std::size_t size) {
    if (::send(fd_, data, size, MSG_NOSIGNAL) != static_cast<ssize_t>(size))
      throw std::runtime_error("send failed");
  }
  // False when the server closed the connection first.
  bool recv_bytes(void* data, std::size_t size) {
    auto* out = static_cast<char*>(data);
    for (std::size_t got = 0; got < size;) {
      const ssize_t n = ::recv(fd_, out + got, size - got, 0);
      if (n <= 0) return false;
      got += static_cast<std::size_t>(n);
    }
    return true;
  }
  // Whether the server has closed the connection (waits up to `ms` for it).
  bool closed_by_server(int ms) {
    timeval tv{ms / 1000, (ms % 1000) * 1000};
    ::setsockopt(fd_, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
    char c;
    const ssize_t n = ::recv(fd_, &c, 1, 0);
    return n == 0 || (n < 0 && errno == ECONNRESET);  // a reset when our bytes went unread
  }
  void close() {
    if (fd_ >= 0) ::close(fd_);
    fd_ = -1;
  }
  int frame_size() const { return frame_; }

 private:
  int fd_ = -1;
  int n_;
  int frame_;
};

// The one-storey frame: floor mass m on a column split into a numerical part k_num (in the
// client's model) and the specimen (served, or elastic k_spec). Explicit Newmark (beta = 0,
// gamma = 1/2) in the form rths's own integrator uses (core/integrators.cpp), the damping c on the
// floor. Per step, the actions an OpenSees explicit analysis sends: 3, 14, 10, then 5.
struct OneStoreyFrame {
  double mass = 1000.0;              // kg
  double k_num = 0.0, k_spec = 0.0;  // N/m
  double damping = 0.0;              // N s/m
  double dt = 0.001;                 // s
};

struct FrameRun {
  std::vector<double> u;  // m, floor displacement per step (row 0 = rest)
  double peak() const {
    double p = 0;
    for (double x : u) p = std::max(p, std::abs(x));
    return p;
  }
};

// specimen(u, v, t) -> force on the floor (N). The motion in m/s^2 at dt, N samples. As OpenSees'
// `analyze N dt` over a Path time series of the motion: steps 1..N, the last at t = N dt, one past
// the record's last sample, where the series gives 0; run.u has N + 1 rows.
inline FrameRun run_frame(const OneStoreyFrame& f, const std::vector<double>& ground,
                          const std::function<double(double, double, double)>& specimen) {
  FrameRun run;
  run.u.assign(ground.size() + 1, 0.0);
  double u = 0, v = 0;
  double a = -ground[0];  // at rest: m a = -m a_g
  const double effective = f.mass + 0.5 * f.dt * f.damping;
  for (std::size_t k = 1; k <= ground.size(); ++k) {
    const double u_next = u + f.dt * v + (0.5 * f.dt * f.dt) * a;
    const double v_next = v + f.dt * a;
    const double t = static_cast<double>(k) * f.dt;
    const double r = f.k_num * u_next + specimen(u_next, v_next, t);
    const double ground_k = k < ground.size() ? ground[k] : 0.0;
    double rhs = -f.mass * ground_k - r;
    rhs -= f.damping * (v + (0.5 * f.dt) * a);
    const double a_next = rhs / effective;
    v += (0.5 * f.dt) * (a + a_next);
    u = u_next;
    a = a_next;
    run.u[k] = u;
  }
  return run;
}

// The specimen served over the protocol: basic DOFs (node 1 fixed, node 2 the floor), actions
// 3, 14, 10, 5 per step; the floor's force is basic force 2.
inline std::function<double(double, double, double)> served_specimen(GenericClient& client) {
  return [&client](double u, double v, double t) {
    client.set_trial({0.0, u}, {0.0, v}, {0.0, 0.0}, t);
    client.ask(14);
    const std::vector<double> force = client.ask(10);
    client.send_action(5);
    return force[1];
  };
}

}  // namespace rths::test
