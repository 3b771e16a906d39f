#include "transport/dds.h"

#include <dds/dds.h>

#include <cstring>
#include <memory>
#include <stdexcept>

#include "envelope.h"

namespace rths::transport::dds {
namespace {

// QoS objects are created, applied and freed at once.
struct QosDeleter {
  void operator()(dds_qos_t* qos) const { dds_delete_qos(qos); }
};
using QosPtr = std::unique_ptr<dds_qos_t, QosDeleter>;

QosPtr make_qos(const QosSpec& spec) {
  QosPtr qos(dds_create_qos());
  if (!qos) throw std::runtime_error("dds_create_qos: out of memory");
  dds_qset_reliability(qos.get(), DDS_RELIABILITY_RELIABLE, DDS_MSECS(spec.max_blocking.count()));
  dds_qset_history(qos.get(), DDS_HISTORY_KEEP_LAST, spec.history_depth);
  dds_qset_durability(qos.get(), DDS_DURABILITY_VOLATILE);
  return qos;
}

}  // namespace

std::int32_t check(std::int32_t rc, const std::string& what) {
  if (rc < 0) throw std::runtime_error(what + ": " + dds_strretcode(rc));
  return rc;
}

Entity& Entity::operator=(Entity&& other) noexcept {
  if (this != &other) {
    if (handle_ > 0) dds_delete(handle_);
    handle_ = other.release();
  }
  return *this;
}

Entity::~Entity() {
  // A child already deleted with its participant returns an error here; nothing to do about it.
  if (handle_ > 0) dds_delete(handle_);
}

Handle Entity::release() {
  const Handle h = handle_;
  handle_ = 0;
  return h;
}

namespace {

QosPtr make_participant_qos(const Properties& properties) {
  if (properties.empty()) return nullptr;
  QosPtr qos(dds_create_qos());
  if (!qos) throw std::runtime_error("dds_create_qos: out of memory");
  for (const auto& [name, value] : properties)
    dds_qset_prop(qos.get(), name.c_str(), value.c_str());
  return qos;
}

}  // namespace

Participant::Participant(std::uint32_t domain_id, const Properties& properties)
    : entity_(
          check(dds_create_participant(domain_id, make_participant_qos(properties).get(), nullptr),
                "dds_create_participant(domain " + std::to_string(domain_id) +
                    (properties.empty() ? ")" : ", with DDS Security)"))) {}

EnvelopeTopic::EnvelopeTopic(const Participant& participant, const std::string& name,
                             const QosSpec& qos)
    : entity_(check(dds_create_topic(participant.get(), &rths_dds_Envelope_desc, name.c_str(),
                                     make_qos(qos).get(), nullptr),
                    "dds_create_topic(" + name + ")")) {}

Writer::Writer(const Participant& participant, const EnvelopeTopic& topic, const QosSpec& qos)
    : entity_(check(dds_create_writer(participant.get(), topic.get(), make_qos(qos).get(), nullptr),
                    "dds_create_writer")) {}

int Writer::matched_readers() const {
  dds_publication_matched_status_t status{};
  check(dds_get_publication_matched_status(entity_.get(), &status),
        "dds_get_publication_matched_status");
  return static_cast<int>(status.current_count);
}

Guid Writer::guid() const {
  dds_guid_t g{};
  check(dds_get_guid(entity_.get(), &g), "dds_get_guid");
  Guid out{};
  static_assert(sizeof g.v == sizeof(Guid));
  std::memcpy(out.data(), g.v, out.size());
  return out;
}

namespace {

struct ListenerDeleter {
  void operator()(dds_listener_t* listener) const { dds_delete_listener(listener); }
};

dds_entity_t make_reader(dds_entity_t participant, dds_entity_t topic, const QosSpec& qos,
                         DataAvailable on_data, void* arg) {
  std::unique_ptr<dds_listener_t, ListenerDeleter> listener;
  if (on_data) {
    listener.reset(dds_create_listener(arg));
    if (!listener) throw std::runtime_error("dds_create_listener: out of memory");
    dds_lset_data_available(listener.get(), on_data);
  }
  return check(dds_create_reader(participant, topic, make_qos(qos).get(), listener.get()),
               "dds_create_reader");
}

}  // namespace

Reader::Reader(const Participant& participant, const EnvelopeTopic& topic, const QosSpec& qos,
               DataAvailable on_data, void* arg)
    : entity_(make_reader(participant.get(), topic.get(), qos, on_data, arg)) {}

void Reader::clear_listener() {
  check(dds_set_listener(entity_.get(), nullptr), "dds_set_listener");
}

int Reader::matched_writers() const {
  dds_subscription_matched_status_t status{};
  check(dds_get_subscription_matched_status(entity_.get(), &status),
        "dds_get_subscription_matched_status");
  return static_cast<int>(status.current_count);
}

std::optional<Guid> publication_guid(Handle reader, std::uint64_t publication_handle) {
  dds_builtintopic_endpoint_t* found = dds_get_matched_publication_data(reader, publication_handle);
  if (!found) return std::nullopt;
  Guid out{};
  std::memcpy(out.data(), found->key.v, out.size());
  dds_builtintopic_free_endpoint(found);
  return out;
}

}  // namespace rths::transport::dds
