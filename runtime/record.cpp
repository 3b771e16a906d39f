#include "runtime/record.h"

#include <google/protobuf/io/coded_stream.h>
#include <google/protobuf/io/zero_copy_stream_impl_lite.h>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <iterator>
#include <stdexcept>

namespace rths::runtime {

RecordWriter::RecordWriter(const std::filesystem::path& path) : path_(path) {
  file_ = std::fopen(path.c_str(), "wb");
  if (!file_)
    throw std::runtime_error("cannot create run record " + path.string() + ": " +
                             std::strerror(errno));
}

RecordWriter::~RecordWriter() {
  if (file_) std::fclose(file_);
}

void RecordWriter::write(const RecordEntry& entry) {
  buffer_.clear();
  {
    google::protobuf::io::StringOutputStream raw(&buffer_);
    google::protobuf::io::CodedOutputStream coded(&raw);
    coded.WriteVarint32(static_cast<std::uint32_t>(entry.ByteSizeLong()));
    entry.SerializeToCodedStream(&coded);
  }
  if (std::fwrite(buffer_.data(), 1, buffer_.size(), file_) != buffer_.size() ||
      std::fflush(file_) != 0)
    throw std::runtime_error("cannot write run record " + path_.string() + ": " +
                             std::strerror(errno));
}

AsyncRecordWriter::AsyncRecordWriter(const std::filesystem::path& path, std::size_t capacity,
                                     std::size_t slot_bytes)
    : path_(path), slots_(capacity) {
  if (capacity == 0) throw std::invalid_argument("record queue capacity must be >= 1");
  file_ = std::fopen(path.c_str(), "wb");
  if (!file_)
    throw std::runtime_error("cannot create run record " + path.string() + ": " +
                             std::strerror(errno));
  for (std::string& slot : slots_) slot.reserve(slot_bytes);
  sem_init(&wake_, 0, 0);
  writer_ = std::thread([this] {
    for (;;) {
      while (sem_wait(&wake_) != 0 && errno == EINTR) {
      }
      drain();
      if (stopping_.load(std::memory_order_acquire)) {
        drain();
        return;
      }
    }
  });
}

AsyncRecordWriter::~AsyncRecordWriter() {
  try {
    close();
  } catch (const std::exception&) {
    // A destructor cannot report; close() is where a caller learns of a write error.
  }
}

bool AsyncRecordWriter::append(const RecordEntry& entry) {
  const std::uint64_t tail = tail_.load(std::memory_order_relaxed);
  if (tail - head_.load(std::memory_order_acquire) >= slots_.size()) {
    dropped_.fetch_add(1, std::memory_order_relaxed);
    return false;
  }
  std::string& slot = slots_[tail % slots_.size()];
  const std::size_t size = entry.ByteSizeLong();
  const std::size_t prefix = google::protobuf::io::CodedOutputStream::VarintSize32(
      static_cast<std::uint32_t>(size));
  slot.resize(prefix + size);
  auto* bytes = reinterpret_cast<std::uint8_t*>(slot.data());
  bytes = google::protobuf::io::CodedOutputStream::WriteVarint32ToArray(
      static_cast<std::uint32_t>(size), bytes);
  entry.SerializeWithCachedSizesToArray(bytes);
  tail_.store(tail + 1, std::memory_order_release);
  sem_post(&wake_);
  return true;
}

void AsyncRecordWriter::drain() {
  std::uint64_t head = head_.load(std::memory_order_relaxed);
  const std::uint64_t tail = tail_.load(std::memory_order_acquire);
  if (head == tail) return;
  for (; head < tail; ++head) {
    const std::string& slot = slots_[head % slots_.size()];
    if (!failed_.load(std::memory_order_relaxed) &&
        std::fwrite(slot.data(), 1, slot.size(), file_) != slot.size()) {
      write_errno_ = errno;
      failed_.store(true, std::memory_order_relaxed);
    }
    if (observer_) observer_->on_entry(slot);
    head_.store(head + 1, std::memory_order_release);
    written_.fetch_add(1, std::memory_order_relaxed);
  }
  if (!failed_.load(std::memory_order_relaxed) && std::fflush(file_) != 0) {
    write_errno_ = errno;
    failed_.store(true, std::memory_order_relaxed);
  }
}

void AsyncRecordWriter::close() {
  if (closed_) return;
  closed_ = true;
  stopping_.store(true, std::memory_order_release);
  sem_post(&wake_);
  writer_.join();
  sem_destroy(&wake_);
  const bool failed = failed_.load();
  if (file_) std::fclose(file_);
  file_ = nullptr;
  if (failed)
    throw std::runtime_error("cannot write run record " + path_.string() + ": " +
                             std::strerror(write_errno_));
}

const RunHeader* RecordContents::header() const {
  for (const auto& e : entries)
    if (e.has_header()) return &e.header();
  return nullptr;
}

const RunFooter* RecordContents::footer() const {
  for (const auto& e : entries)
    if (e.has_footer()) return &e.footer();
  return nullptr;
}

std::vector<const StepRecord*> RecordContents::steps() const {
  std::vector<const StepRecord*> out;
  for (const auto& e : entries)
    if (e.has_step()) out.push_back(&e.step());
  return out;
}

RecordContents read_record(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error("cannot open run record " + path.string());
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  RecordContents contents;
  google::protobuf::io::ArrayInputStream raw(bytes.data(), static_cast<int>(bytes.size()));
  google::protobuf::io::CodedInputStream coded(&raw);
  coded.SetTotalBytesLimit(INT32_MAX);
  for (;;) {
    const int start = coded.CurrentPosition();
    if (start == static_cast<int>(bytes.size())) break;
    std::uint32_t size = 0;
    if (!coded.ReadVarint32(&size) ||
        static_cast<std::size_t>(coded.CurrentPosition()) + size > bytes.size()) {
      contents.truncated = true;
      contents.warning = path.string() + ": truncated after " +
                         std::to_string(contents.entries.size()) + " complete entries (byte " +
                         std::to_string(start) + " of " + std::to_string(bytes.size()) +
                         "); the rest was lost";
      break;
    }
    const auto limit = coded.PushLimit(static_cast<int>(size));
    RecordEntry entry;
    if (!entry.ParseFromCodedStream(&coded) || !coded.ConsumedEntireMessage())
      throw std::runtime_error(path.string() + ": corrupt entry " +
                               std::to_string(contents.entries.size()) + " at byte " +
                               std::to_string(start));
    coded.PopLimit(limit);
    contents.entries.push_back(std::move(entry));
  }
  return contents;
}

}  // namespace rths::runtime
