#pragma once
// Run record: a stream of rths.runtime.RecordEntry: the header, the inputs, then steps and events,
// then the header again and a footer when the run ended in an orderly way (a record without a
// footer was cut short). Each entry is flushed to the OS at once, so a crash of the writer loses
// at most the entry being written.
// Header copies: both writers write the last header again (the same frame, byte for byte) before
// the first step and then before every kHeaderRepeatSteps-th step, so a record cut anywhere after
// its first step holds two copies, and a damaged copy costs nothing while another reads. A record
// whose every copy is damaged is still read: the reader assumes a header from the steps (dofs and
// actuators from the step frames' sizes, dt from the step times, links from the link samples, the
// study from the inputs entry when it is intact) and says so (RecordContents::assumed).
//
// Format (version 2), every integer little-endian:
//   file      preamble frame*
//   preamble  "RTHSREC" 0x02                                  (8 bytes: magic, format version)
//   frame     sync F3 7A 1C B5 | size u32 | crc32c(payload) u32 | crc32c(the 12 bytes before) u32
//             | payload: one RecordEntry, `size` bytes          (16 bytes + payload)
// Every entry, the header included, carries its checksum (CRC-32C, util/crc32c.h); the frame
// header has its own, so a damaged frame is told from one a crash cut off (a valid frame header
// whose payload runs past the end of the file). Adding a field to RunHeader (or to any entry) is
// compatible: the reader ignores fields it does not know, and the checksum covers them all.
//
// Reading (read_record, parse_record) verifies every checksum and salvages: after a damaged
// region it resynchronises on the next frame whose sync and frame-header checksum hold, so every
// intact entry around a damaged one is kept, and each damaged region is reported (bytes, and the
// steps it held, from the intact steps around it). A frame whose size is impossible (its payload
// would run past the end of the file, or its payload checksum fails) is not trusted to say where
// the next frame starts: the reader looks for the next frame header after its own, so a forged or
// damaged size never hides the intact frames behind it; only a frame with no frame header after
// it is a truncation (a crash cut it). The reader's work is linear in the record's size, whatever
// its frame headers claim (runtime/record/frame_scan.h). A record written before checksums (no
// preamble; varint size, then the entry) still reads, unverified, with a warning.
// The one reader of a record's content is runtime::measure_run (runtime/record/measurements.h),
// over what read_record returns.

#include <semaphore.h>

#include <atomic>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <thread>
#include <utility>
#include <vector>

#include "rths/proto/runtime.pb.h"

namespace rths::runtime {

inline constexpr std::size_t kRecordPreambleBytes = 8;
inline constexpr std::size_t kRecordFrameHeaderBytes = 16;
// Steps between two header copies (see above): about 1 % of a record's bytes for a header of a
// few kB and steps of ~200 bytes.
inline constexpr std::int64_t kHeaderRepeatSteps = 1000;

// Where the writers put header copies: told of each frame as it is written, it says before which
// step frame the last header goes again. Writer-side only; one thread.
class HeaderRepeat {
 public:
  // The frame (as in the file) to write before a frame of this kind, empty for none.
  std::string_view copy_before(RecordEntry::EntryCase kind) const;
  // After `frame` (as in the file, a header copy included) was written.
  void written(std::string_view frame, RecordEntry::EntryCase kind);

 private:
  std::string header_frame_;  // the last header written, sealed
  int copies_ = 0;            // header frames written
  std::int64_t steps_since_ = 0;
};

// The 8 bytes a record of this format starts with.
std::string_view record_preamble();

// Fills the frame header at `frame` for the `payload_size` payload bytes that follow it at
// frame + kRecordFrameHeaderBytes (sync, size, both checksums).
void seal_record_frame(char* frame, std::uint32_t payload_size);

// Appends the entry's frame to `out`.
void append_record_frame(const RecordEntry& entry, std::string& out);

class RecordWriter {
 public:
  // Creates (truncates) the file and writes the preamble; throws std::runtime_error naming it
  // when it cannot.
  explicit RecordWriter(const std::filesystem::path& path);
  ~RecordWriter();
  RecordWriter(const RecordWriter&) = delete;
  RecordWriter& operator=(const RecordWriter&) = delete;
  // Appends and flushes one entry (after a header copy when one is due). Throws on a write error.
  void write(const RecordEntry& entry);
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
  std::FILE* file_ = nullptr;
  std::string buffer_;
  HeaderRepeat repeat_;
};

// Sees each entry after the writer thread wrote it, on that thread (never on the thread that
// appends): `frame` is the entry's frame as in the file (kRecordFrameHeaderBytes of frame header,
// then the entry's bytes). It must return quickly and must not throw; it is how a live view
// follows a run without touching the loop.
class RecordObserver {
 public:
  virtual ~RecordObserver() = default;
  virtual void on_entry(std::string_view frame) = 0;
};

// The real-time loop's record writer: the loop hands each entry to a writer thread through a
// bounded single-producer single-consumer ring of preallocated slots, so append() neither blocks
// nor does I/O, and, once every slot has grown to the largest entry, allocates nothing.
//   append(entry)   serialises into the next free slot and wakes the writer (sem_post, which never
//                   blocks). Ring full (the writer is more than `capacity` entries behind): the entry
//                   is dropped and counted (dropped()); the caller reports the gap, it is never silent.
//   writer thread   seals each slot's frame (checksums), writes it (after a header copy when one
//                   is due: HeaderRepeat) and flushes every time the ring runs empty. The first
//                   failed write or flush (disk full, I/O error, file size limit) is kept
//                   (failed(), failure()); nothing is written after it, so the file stays a
//                   readable prefix. The loop polls failed() once a step and stops the run: a
//                   record that cannot be written is a run that keeps nothing.
//   close()         (and the destructor) writes everything queued, then joins the writer.
// Crash bound: kill -9 of the process loses at most the entries still in the ring, which is at
// most `capacity` (entries are written in order, so the file is a prefix of what was appended:
// no gap, at worst a cut last entry that read_record reports as truncated).
// append() is for one producer thread; dropped(), written() and failed() from any thread;
// failure() once failed() is true.
class AsyncRecordWriter {
 public:
  // Creates (truncates) the file; throws std::runtime_error naming it when it cannot.
  // slot_bytes: the room each slot reserves up front (it grows for a larger entry).
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
  // Entries appended and written (header copies the writer adds are not counted).
  std::uint64_t written() const { return written_.load(std::memory_order_relaxed); }
  // A write or flush failed; the writer writes nothing more.
  bool failed() const { return failed_.load(std::memory_order_acquire); }
  // "cannot write run record FILE: REASON" (empty before failed()).
  std::string failure() const;
  std::size_t capacity() const { return slots_.size(); }
  const std::filesystem::path& path() const { return path_; }
  // Set before the first append(); null (the default) for none. Not owned; must outlive close().
  void set_observer(RecordObserver* observer) { observer_ = observer; }

 private:
  void drain();
  // Writer thread: the header copy due before it, then the sealed frame; a failure is kept.
  void write_frame(std::string_view frame, RecordEntry::EntryCase kind);
  void fail(int error);  // writer thread: keeps the first error
  RecordObserver* observer_ = nullptr;
  std::filesystem::path path_;
  std::FILE* file_ = nullptr;
  std::vector<std::string> slots_;
  std::vector<RecordEntry::EntryCase> kinds_;     // each slot's entry kind, set by append()
  HeaderRepeat repeat_;                           // writer thread
  std::atomic<std::uint64_t> head_{0}, tail_{0};  // consumed, produced (monotonic counts)
  std::atomic<std::uint64_t> dropped_{0}, written_{0};
  std::atomic<bool> stopping_{false}, failed_{false};
  int write_errno_ = 0;
  sem_t wake_;
  std::thread writer_;
  bool closed_ = false;
};

// A damaged region of a record: bytes that hold no intact entry, skipped by the reader.
struct RecordLoss {
  std::uint64_t first_byte = 0, end_byte = 0;  // [first_byte, end_byte) of the file
  std::int64_t last_step_before = -1;          // the last intact step before the region; -1: none
  std::int64_t first_step_after = -1;          // the first intact step after it; -1: none
  // e.g. "bytes 1234-1455 (222 bytes): steps 1059-1061 lost"; "... : no step lost (an entry
  // between step 12 and step 13)"; "...: after step 1058 (every later step lost)".
  std::string describe() const;
};

struct RecordContents {
  std::string source;  // the file (or what parse_record was told), for messages
  std::vector<RecordEntry> entries;
  std::vector<std::uint64_t> offsets;  // byte offset of each entry's frame (entries' order)
  bool truncated = false;          // the file ends inside an entry; everything before it was read
  std::uint64_t truncated_at = 0;  // byte where that cut entry starts
  bool checksummed = true;         // false: an old record without checksums (read unverified)
  std::vector<RecordLoss> losses;  // damaged regions, in file order (each skipped)
  // The payload CRC-32C of the first intact inputs entry (what RunHeader.inputs_crc32c names);
  // 0 when there is none or the record has no checksums.
  std::uint32_t inputs_crc32c = 0;
  // Bytes the reader searched or checksummed (frame_scan.h): at most 16 x the record's size.
  std::uint64_t examined_bytes = 0;
  std::string warning;  // what the reader has to say: truncation, no checksums, losses, assumed
  // No intact header: the one assumed from the steps (see above); `assumed` says what was
  // assumed and from what ("" when an intact header was read).
  std::optional<RunHeader> assumed_header;
  std::string assumed;
  // The first intact header copy; nullptr when every copy is damaged.
  const RunHeader* header() const;
  // header(), else the assumed one: what a table of the steps is sized and timed by.
  const RunHeader* header_or_assumed() const;
  const RunFooter* footer() const;
  // The study as run: the inputs entry's (every file it read embedded), else, for a record
  // without one (older, or its inputs entry damaged), the header's; nullptr without a header.
  const config::Study* study_as_run() const;
  std::vector<const StepRecord*> steps() const;
  bool lost_entries() const { return !losses.empty(); }
  // Step numbers missing from the intact steps, as closed ranges [first, last]: gaps in the
  // sequence from step 0, and, when the footer is intact, the steps after the last intact one
  // up to the footer's count.
  std::vector<std::pair<std::int64_t, std::int64_t>> missing_steps() const;
  // "FILE: N damaged regions (B bytes) skipped: <describe>; ...", empty when nothing was lost.
  std::string loss_report() const;
};

// How many values each StepRecord's displacement, velocity and acceleration hold: one per DOF the
// header names in recorded_dofs (what the recorders kept), or every DOF of the model when it names
// none.
int recorded_columns(const RunHeader& header);
// The DOFs (0-based, ascending) of those columns: recorded_dofs, or 0..dofs-1.
std::vector<int> recorded_dofs(const RunHeader& header);

// Reads every intact entry (see the format above). Throws std::runtime_error naming the file
// when it cannot be opened, or when it is neither a record of this format nor an old record that
// starts with a header and parses to the end.
RecordContents read_record(const std::filesystem::path& path);
// The same over bytes in memory; `source` names them in messages.
RecordContents parse_record(std::string_view bytes, const std::string& source);

}  // namespace rths::runtime
