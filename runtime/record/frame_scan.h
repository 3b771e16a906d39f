#pragma once
// Finding and checking a run record's frames (format: runtime/record/record.h) with work linear in
// the record's size, whatever its bytes claim.
//
// A frame header says how long its payload is, and after a damaged frame the reader tries every
// frame header after it: crafted headers whose claimed payloads overlap (each reaching to the end
// of the file, or to the next) would cost a checksum over the same bytes once per header, which is
// quadratic. The scanner checks each byte once directly; a payload that overlaps bytes already
// checked is checked from prefix checksums instead (CRC-32C of [0, end) kept every
// kCheckpointBytes, built in one pass the first time one is needed): the CRC-32C of [a, b) is
// crc[0, b) xor crc[0, a) shifted by b - a bytes (zlib's crc32_combine, solved for the second
// part), O(kCheckpointBytes + log size) per frame.
//
// Work (examined()): bytes the scanner ran a checksum over, plus bytes it searched for a sync. Per
// byte of the record: searched once, checksummed once directly and once into the checkpoints; per
// frame header found: 24 bytes of header checks and at most 2 (kCheckpointBytes - 1) bytes to
// reach the checkpoints; per sync pattern (4 bytes apart at least) 12. Frame headers whose
// checksums hold lie 8 bytes apart at least, so a record of n bytes costs at most 16 n, whatever
// it holds (tested with crafted headers: tests/runtime/frame_scan_test.cpp). One thread; the
// bytes must outlive it; the callers ask for frames in increasing order.

#include <cstddef>
#include <cstdint>
#include <string_view>
#include <vector>

namespace rths::runtime {

// The 4 bytes every frame starts with.
inline constexpr unsigned char kRecordFrameSync[4] = {0xF3, 0x7A, 0x1C, 0xB5};

// What starts at a byte.
enum class Frame {
  kNone,     // no frame header (sync and frame-header checksum) there
  kIntact,   // a frame whose payload checksum holds
  kDamaged,  // a genuine frame header whose payload is damaged
  kCut,      // a genuine frame header whose payload runs past the end (a crash cut it)
};

// The CRC-32C of B given crc_ab = CRC-32C(A + B), crc_a = CRC-32C(A) and B's length.
std::uint32_t crc32c_of_suffix(std::uint32_t crc_ab, std::uint32_t crc_a, std::uint64_t b_size);

class FrameScanner {
 public:
  static constexpr std::size_t kCheckpointBytes = 32;

  explicit FrameScanner(std::string_view bytes) : bytes_(bytes) {}
  // What starts at `at` (fewer than a frame header's bytes left: kNone); `size` gets the payload
  // size a frame header there claims.
  Frame frame_at(std::size_t at, std::uint32_t* size);
  // The first frame header at or after `from` (its payload is not checked); npos when none.
  std::size_t next_frame(std::size_t from);
  std::uint64_t examined() const { return examined_; }

 private:
  bool header_at(std::size_t at);  // sync and frame-header checksum
  std::uint32_t payload_crc(std::size_t first, std::size_t size);
  std::uint32_t prefix_crc(std::size_t end);  // CRC-32C of [0, end), from the checkpoints
  std::string_view bytes_;
  std::size_t checked_until_ = 0;           // payload bytes below it were checked directly
  std::vector<std::uint32_t> checkpoints_;  // CRC-32C of [0, i x kCheckpointBytes)
  std::uint64_t examined_ = 0;
};

}  // namespace rths::runtime
