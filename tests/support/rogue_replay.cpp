#include "tests/support/rogue_replay.h"

#include <dds/dds.h>

#include <chrono>
#include <memory>
#include <stdexcept>
#include <thread>
#include <vector>

#include "envelope.h"
#include "transport/topic_scope.h"

namespace rths::rogue {

namespace {

dds_entity_t checked(dds_entity_t rc, const std::string& what) {
  if (rc < 0) throw std::runtime_error(what + ": " + dds_strretcode(rc));
  return rc;
}

struct QosDeleter {
  void operator()(dds_qos_t* qos) const { dds_delete_qos(qos); }
};

// As the run's own endpoints (reliable, KEEP_LAST 64, volatile), and deaf to this participant's
// own writes, so a replay is never replayed again.
std::unique_ptr<dds_qos_t, QosDeleter> run_qos() {
  std::unique_ptr<dds_qos_t, QosDeleter> qos(dds_create_qos());
  dds_qset_reliability(qos.get(), DDS_RELIABILITY_RELIABLE, DDS_SECS(1));
  dds_qset_history(qos.get(), DDS_HISTORY_KEEP_LAST, 64);
  dds_qset_durability(qos.get(), DDS_DURABILITY_VOLATILE);
  dds_qset_ignorelocal(qos.get(), DDS_IGNORELOCAL_PARTICIPANT);
  return qos;
}

// One topic of the run: what is read off it is written back to it by the rogue's own writer.
struct Tap {
  std::string topic;
  dds_entity_t reader = 0, writer = 0;
};

Tap tap(dds_entity_t participant, const std::string& name) {
  const auto qos = run_qos();
  const dds_entity_t topic = checked(
      dds_create_topic(participant, &rths_dds_Envelope_desc, name.c_str(), qos.get(), nullptr),
      "dds_create_topic(" + name + ")");
  return {name, checked(dds_create_reader(participant, topic, qos.get(), nullptr), "reader"),
          checked(dds_create_writer(participant, topic, qos.get(), nullptr), "writer")};
}

// Re-publishes everything `t` has received since the last call, unchanged; counts it.
void replay_taken(const Tap& t, std::map<std::string, long>& replayed) {
  constexpr int kBatch = 16;
  void* samples[kBatch] = {};
  dds_sample_info_t infos[kBatch];
  for (;;) {
    const dds_return_t n = dds_take(t.reader, samples, infos, kBatch, kBatch);
    if (n <= 0) return;
    for (int i = 0; i < n; ++i) {
      if (!infos[i].valid_data) continue;
      const auto* s = static_cast<const rths_dds_Envelope*>(samples[i]);
      checked(dds_write(t.writer, s), "dds_write");
      ++replayed[t.topic + " kind " + std::to_string(s->kind)];
    }
    dds_return_loan(t.reader, samples, n);
    if (n < kBatch) return;
  }
}

}  // namespace

std::map<std::string, long> replay(int domain, double seconds,
                                   const volatile std::sig_atomic_t& stop) {
  const dds_entity_t participant =
      checked(dds_create_participant(static_cast<dds_domainid_t>(domain), nullptr, nullptr),
              "dds_create_participant");
  std::map<std::string, long> replayed;
  try {
    std::vector<Tap> taps;
    // The run's topics under this process's scope (RTHS_DDS_SCOPE), as its endpoints name them.
    const std::string prefix = transport::scoped_topic_prefix();
    for (const char* name : {"_node1_up", "_node2_up", "_node1_down", "_node2_down"})
      taps.push_back(tap(participant, prefix + name));
    const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
    while (std::chrono::steady_clock::now() < end && !stop) {
      for (const Tap& t : taps) replay_taken(t, replayed);
      std::this_thread::sleep_for(std::chrono::microseconds(500));
    }
  } catch (...) {
    dds_delete(participant);
    throw;
  }
  dds_delete(participant);
  return replayed;
}

}  // namespace rths::rogue
