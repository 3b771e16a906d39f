// dds_probe: one DDS participant for the security tests, as a separate process.
//   dds_probe send|receive --domain D --prefix P --as coordinator|node [--node-id N] [--peer M]
//             [--security NODE_DIR [--identity ID]] --seconds S
// send:    an rths endpoint (coordinator: writes <P>_node<M>_down; node N: writes <P>_node<N>_up)
//          that writes one message every 5 ms for S seconds; prints "sent N".
// receive: the same endpoint reading the other way (coordinator: <P>_node<M>_up); counts every
//          message delivered to it for S seconds; prints "received N".
// --identity: the node whose certificate NODE_DIR must hold (default: 0 as coordinator, else
// --node-id); a node identity in the coordinator's role is how a test forges commands.
// Exit 0 when it ran, 2 for refused security documents, 3 when DDS refused (e.g. an entity the
// permissions do not allow), with the reason on stderr.
#include <CLI/CLI.hpp>
#include <chrono>
#include <iostream>
#include <thread>

#include "security/check.h"
#include "transport/dds_endpoint.h"

int main(int argc, char** argv) {
  using namespace rths;
  CLI::App app{"dds_probe"};
  std::string mode, role, security_dir, prefix;
  int domain = -1, node_id = 1, identity = -1, peer = 1;
  double seconds = 1;
  app.add_option("mode", mode)->required()->check(CLI::IsMember({"send", "receive"}));
  app.add_option("--domain", domain)->required();
  app.add_option("--prefix", prefix)->required();
  app.add_option("--as", role)->required()->check(CLI::IsMember({"coordinator", "node"}));
  app.add_option("--node-id", node_id);
  app.add_option("--peer", peer, "coordinator: the node it writes to or listens to");
  app.add_option("--security", security_dir);
  app.add_option("--identity", identity);
  app.add_option("--seconds", seconds);
  CLI11_PARSE(app, argc, argv);
  transport::DdsEndpointOptions options;
  options.domain_id = static_cast<std::uint32_t>(domain);
  options.coordinator = role == "coordinator";
  options.node_id = options.coordinator ? transport::kCoordinatorId : node_id;
  options.topic_prefix = prefix;
  try {
    if (!security_dir.empty())
      options.participant_properties = security::participant_properties(
          security::check_node_security(security_dir, identity >= 0         ? identity
                                                      : options.coordinator ? 0
                                                                            : node_id));
  } catch (const std::exception& e) {
    std::cerr << "dds_probe: " << e.what() << "\n";
    return 2;
  }
  try {
    transport::DdsEndpoint endpoint(options);
    endpoint.listen_to(peer);
    const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
    long count = 0;
    if (mode == "send") {
      transport::Message m;
      m.run_id = "probe";
      m.node_id = options.coordinator ? peer : node_id;
      m.kind = 6;  // HEARTBEAT
      m.payload = "probe";
      while (std::chrono::steady_clock::now() < end) {
        m.step = count++;
        m.sent_ns = 0;
        endpoint.send(m);
        std::this_thread::sleep_for(std::chrono::milliseconds(5));
      }
      std::cout << "sent " << count << std::endl;
    } else {
      while (std::chrono::steady_clock::now() < end)
        if (endpoint.receive(std::chrono::milliseconds(20))) ++count;
      std::cout << "received " << count << std::endl;
    }
    return 0;
  } catch (const std::exception& e) {
    std::cerr << "dds_probe: " << e.what() << "\n";
    return 3;
  }
}
