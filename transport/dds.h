#pragma once
// Thin RAII layer over the Cyclone DDS C API. Every dds_* return code is checked and a failure
// becomes std::runtime_error "<what>: <dds_strretcode>". Entities are deleted in destruction
// order (children before the participant; dds_delete of a participant also deletes children, so
// handles are released without double deletes). This header exposes no DDS type: handles are
// plain int32 (dds_entity_t is int32_t) and the sample type is chosen inside dds.cpp.

#include <array>
#include <chrono>
#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace rths::transport::dds {

using Handle = std::int32_t;
// A DDS entity's GUID: Cyclone's dds_guid_t, 16 bytes (the same bytes from dds_get_guid and as
// the key of a matched publication).
using Guid = std::array<std::uint8_t, 16>;

// Throws std::runtime_error("<what>: <reason>") when rc < 0; returns rc otherwise.
std::int32_t check(std::int32_t rc, const std::string& what);

// Owns one DDS entity; deleting it deletes its children.
class Entity {
 public:
  Entity() = default;
  explicit Entity(Handle handle) : handle_(handle) {}
  Entity(const Entity&) = delete;
  Entity& operator=(const Entity&) = delete;
  Entity(Entity&& other) noexcept : handle_(other.release()) {}
  Entity& operator=(Entity&& other) noexcept;
  ~Entity();
  Handle get() const { return handle_; }
  Handle release();

 private:
  Handle handle_ = 0;
};

// Reliable, KEEP_LAST `depth`, volatile: what every rths topic, reader and writer uses.
struct QosSpec {
  int history_depth = 64;
  std::chrono::milliseconds max_blocking{1000};
};

// Name/value QoS properties of a participant (dds_qset_prop), e.g. the "dds.sec.*" ones that
// switch DDS Security on. Empty = none.
using Properties = std::vector<std::pair<std::string, std::string>>;

class Participant {
 public:
  explicit Participant(std::uint32_t domain_id, const Properties& properties = {});
  Handle get() const { return entity_.get(); }

 private:
  Entity entity_;
};

// A topic of the envelope type.
class EnvelopeTopic {
 public:
  EnvelopeTopic(const Participant& participant, const std::string& name, const QosSpec& qos);
  Handle get() const { return entity_.get(); }

 private:
  Entity entity_;
};

class Writer {
 public:
  Writer(const Participant& participant, const EnvelopeTopic& topic, const QosSpec& qos);
  Handle get() const { return entity_.get(); }
  int matched_readers() const;
  // This writer's GUID, as its readers see it.
  Guid guid() const;

 private:
  Entity entity_;
};

// Called on Cyclone's receive thread when data arrives (after the sample is stored).
using DataAvailable = void (*)(Handle reader, void* arg);

class Reader {
 public:
  // With `on_data` set, it runs on Cyclone's receive thread for every arrival (arg passed back);
  // it must not block and `arg` must outlive the reader (or clear_listener()).
  Reader(const Participant& participant, const EnvelopeTopic& topic, const QosSpec& qos,
         DataAvailable on_data = nullptr, void* arg = nullptr);
  // Removes the listener; returns once no invocation of it is in progress.
  void clear_listener();
  Handle get() const { return entity_.get(); }
  int matched_writers() const;

 private:
  Entity entity_;
};

// The GUID of the writer matched to `reader` whose samples carry `publication_handle` (their
// sample info's), or nullopt when it is not (or no longer) matched. Allocates (Cyclone copies the
// writer's names and QoS out): look it up once per writer, not per sample. Any thread.
std::optional<Guid> publication_guid(Handle reader, std::uint64_t publication_handle);

}  // namespace rths::transport::dds
