#pragma once
// Run record: a stream of rths.runtime.RecordEntry, each written length-delimited (varint size,
// then the bytes) and flushed to the OS at once, so a crash of the writer loses at most the entry
// being written. A record is one header, then steps and events, then a footer when the run ended
// in an orderly way (a record without a footer was cut short).

#include <semaphore.h>

#include <atomic>
#include <cstdio>
#include <filesystem>
#include <string>
#include <string_view>
#include <thread>
#include <vector>

#include "rths/proto/runtime.pb.h"

namespace rths::runtime {

class RecordWriter {
 public:
  // Creates (truncates) the file; throws std::runtime_error naming it when it cannot.
  explicit RecordWriter(const std::filesystem::path& path);
  ~RecordWriter();
  RecordWriter(const RecordWriter&) = delete;
  RecordWriter& operator=(const RecordWriter&) = delete;
  // Appends and flushes one entry. Throws on a write error.
  void write(const RecordEntry& entry);
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
  std::FILE* file_ = nullptr;
  std::string buffer_;
};

// Sees each entry after the writer thread wrote it, on that thread (never on the thread that
// appends): `delimited` is the entry as in the file (varint size, then the bytes). It must return
// quickly and must not throw; it is how a live view follows a run without touching the loop.
class RecordObserver {
 public:
  virtual ~RecordObserver() = default;
  virtual void on_entry(std::string_view delimited) = 0;
};

// The real-time loop's record writer: the loop hands each entry to a writer thread through a
// bounded single-producer single-consumer ring of preallocated slots, so append() neither blocks
// nor does I/O, and, once every slot has grown to the largest entry, allocates nothing.
//   append(entry)   serialises into the next free slot and wakes the writer (sem_post, which never
//                   blocks). Ring full (the writer is more than `capacity` entries behind): the entry
//                   is dropped and counted (dropped()); the caller reports the gap, it is never silent.
//   writer thread   writes each slot length-delimited and flushes every time the ring runs empty.
//   close()         (and the destructor) writes everything queued, then joins the writer.
// Crash bound: kill -9 of the process loses at most the entries still in the ring, which is at
// most `capacity` (entries are written in order, so the file is a prefix of what was appended:
// no gap, at worst a cut last entry that read_record reports as truncated).
// append() is for one producer thread; dropped() and written() may be read from any thread.
class AsyncRecordWriter {
 public:
  // Creates (truncates) the file; throws std::runtime_error naming it when it cannot.
  // @pre capacity >= 1
  AsyncRecordWriter(const std::filesystem::path& path, std::size_t capacity = 4096,
                    std::size_t slot_bytes = 4096);
  ~AsyncRecordWriter();
  AsyncRecordWriter(const AsyncRecordWriter&) = delete;
  AsyncRecordWriter& operator=(const AsyncRecordWriter&) = delete;
  // False when the ring was full and the entry dropped.
  bool append(const RecordEntry& entry);
  // Writes what is queued and stops the writer. Throws std::runtime_error naming the file when a
  // write failed (at any time since the start).
  void close();
  std::uint64_t dropped() const { return dropped_.load(std::memory_order_relaxed); }
  std::uint64_t written() const { return written_.load(std::memory_order_relaxed); }
  std::size_t capacity() const { return slots_.size(); }
  const std::filesystem::path& path() const { return path_; }
  // Set before the first append(); null (the default) for none. Not owned; must outlive close().
  void set_observer(RecordObserver* observer) { observer_ = observer; }

 private:
  void drain();
  RecordObserver* observer_ = nullptr;
  std::filesystem::path path_;
  std::FILE* file_ = nullptr;
  std::vector<std::string> slots_;
  std::atomic<std::uint64_t> head_{0}, tail_{0};  // consumed, produced (monotonic counts)
  std::atomic<std::uint64_t> dropped_{0}, written_{0};
  std::atomic<bool> stopping_{false}, failed_{false};
  int write_errno_ = 0;
  sem_t wake_;
  std::thread writer_;
  bool closed_ = false;
};

struct RecordContents {
  std::vector<RecordEntry> entries;
  bool truncated = false;  // the file ends inside an entry; everything before it was read
  std::string warning;     // says where, when truncated
  const RunHeader* header() const;
  const RunFooter* footer() const;
  std::vector<const StepRecord*> steps() const;
};

// Reads every complete entry. Throws std::runtime_error naming the file when it cannot be opened
// or an entry is corrupt (not merely cut off).
RecordContents read_record(const std::filesystem::path& path);

}  // namespace rths::runtime
