// The record reader's work is linear in its input (runtime/record/frame_scan.h): crafted frame
// headers whose claimed payloads overlap cost a bounded number of bytes examined per byte (a count,
// not a time), and on random damage the reader salvages exactly what the reader before it did
// (that reader, checking every claimed payload directly, is kept here as the reference).
#include "runtime/record/frame_scan.h"

#include <gtest/gtest.h>

#include <cstring>
#include <iostream>
#include <random>
#include <string>
#include <tuple>
#include <vector>

#include "runtime/node/schema.h"
#include "runtime/record/record.h"
#include "util/crc32c.h"

namespace rths::runtime {
namespace {

std::uint32_t load_le32(const char* at) {
  std::uint32_t value = 0;
  for (int i = 3; i >= 0; --i) value = (value << 8) | static_cast<std::uint8_t>(at[i]);
  return value;
}

void store_le32(std::string& bytes, std::size_t at, std::uint32_t value) {
  for (int i = 0; i < 4; ++i) bytes[at + i] = static_cast<char>((value >> (8 * i)) & 0xFFu);
}

TEST(FrameScan, TheChecksumOfASuffixIsTheDirectOne) {
  std::mt19937 random(7);
  std::string bytes(5000, '\0');
  for (char& c : bytes) c = static_cast<char>(random());
  for (std::size_t a : {0u, 1u, 31u, 32u, 1000u, 4999u})
    for (std::size_t b : {a, a + 1, a + 33, std::size_t{5000}}) {
      if (b > bytes.size()) continue;
      const std::uint32_t ab = util::crc32c(bytes.data(), b), first = util::crc32c(bytes.data(), a);
      EXPECT_EQ(crc32c_of_suffix(ab, first, b - a), util::crc32c(bytes.data() + a, b - a))
          << a << ".." << b;
    }
}

// A frame header at the end of `bytes` claiming `size` payload bytes with payload checksum `crc`.
void append_header(std::string& bytes, std::uint32_t size, std::uint32_t crc) {
  const std::size_t at = bytes.size();
  bytes.append(reinterpret_cast<const char*>(kRecordFrameSync), sizeof kRecordFrameSync);
  bytes.resize(at + kRecordFrameHeaderBytes);
  store_le32(bytes, at + 4, size);
  store_le32(bytes, at + 8, crc);
  store_le32(bytes, at + 12, util::crc32c(bytes.data() + at, 12));
}

RecordEntry header_entry() {
  RecordEntry e;
  e.mutable_header()->set_schema_version(kSchemaVersion);
  e.mutable_header()->set_dt(0.001);
  e.mutable_header()->set_dofs(2);
  e.mutable_header()->set_actuators(1);
  return e;
}

RecordEntry step_entry(std::int64_t k) {
  RecordEntry e;
  e.mutable_step()->set_step(k);
  e.mutable_step()->set_time(0.001 * static_cast<double>(k));
  for (int d = 0; d < 2; ++d) e.mutable_step()->add_displacement(1e-3 * static_cast<double>(k));
  e.mutable_step()->add_command(0.0);
  LinkSample& link = *e.mutable_step()->add_links();
  link.set_node_id(1);
  link.set_round_trip(2e-4);
  return e;
}

// How crafted headers claim their sizes.
enum class Claim {
  kToTheEnd,   // every payload runs to the end of the file
  kToAnother,  // every payload ends at a later crafted header (half-way to the last one)
};

// The preamble and a header, `headers` crafted frame headers 16 bytes apart whose payload
// checksums fail, then steps 0..steps-1 and a footer, every genuine frame intact.
std::string crafted_record(std::size_t headers, Claim claim, int steps) {
  std::string tail;
  for (int k = 0; k < steps; ++k) append_record_frame(step_entry(k), tail);
  RecordEntry footer;
  footer.mutable_footer()->set_status("completed");
  append_record_frame(footer, tail);
  std::string bytes(record_preamble());
  append_record_frame(header_entry(), bytes);
  const std::size_t first = bytes.size(), end = first + 16 * headers + tail.size();
  for (std::size_t i = 0; i < headers; ++i) {
    const std::size_t at = first + 16 * i;
    const std::size_t target = claim == Claim::kToTheEnd ? end : first + 16 * ((i + headers) / 2);
    append_header(bytes, static_cast<std::uint32_t>(target > at + 16 ? target - at - 16 : 0),
                  0xDEADBEEF);
  }
  return bytes + tail;
}

// What the reader salvaged: each entry's offset, each damaged region, the truncation.
using Salvage =
    std::tuple<std::vector<std::uint64_t>, std::vector<std::pair<std::uint64_t, std::uint64_t>>,
               bool, std::uint64_t>;

Salvage salvage_of(const RecordContents& c) {
  std::vector<std::pair<std::uint64_t, std::uint64_t>> losses;
  for (const RecordLoss& loss : c.losses) losses.emplace_back(loss.first_byte, loss.end_byte);
  return {c.offsets, losses, c.truncated, c.truncated_at};
}

TEST(FrameScan, CraftedHeadersWithOverlappingClaimsCostABoundedWorkPerByte) {
  for (Claim claim : {Claim::kToTheEnd, Claim::kToAnother}) {
    const std::string bytes = crafted_record(65536, claim, 100);  // 1 MiB of crafted headers
    ASSERT_GT(bytes.size(), 1000000u);
    const RecordContents read = parse_record(bytes, "crafted.rthsrec");
    EXPECT_LE(read.examined_bytes, 16 * bytes.size()) << static_cast<int>(claim);
    EXPECT_EQ(read.steps().size(), 100u);
    ASSERT_EQ(read.losses.size(), 1u) << read.loss_report();
    EXPECT_EQ(read.losses[0].end_byte - read.losses[0].first_byte, 16u * 65536u);
    EXPECT_NE(read.footer(), nullptr);
    std::cout << "1 MiB of crafted headers ("
              << (claim == Claim::kToTheEnd ? "to the end" : "to another")
              << "): " << read.examined_bytes << " bytes examined for " << bytes.size()
              << " bytes (" << static_cast<double>(read.examined_bytes) / bytes.size()
              << " per byte)\n";
  }
}

// The reader before frame_scan.h: every claimed payload checked directly (quadratic on crafted
// headers, the reference on what is salvaged). Frames from `at`, as parse_frames reads them.
Salvage reference_salvage(std::string_view bytes, std::size_t at) {
  const auto header_at = [&](std::size_t p) {
    return bytes.size() - p >= kRecordFrameHeaderBytes &&
           std::memcmp(bytes.data() + p, kRecordFrameSync, 4) == 0 &&
           load_le32(bytes.data() + p + 12) == util::crc32c(bytes.data() + p, 12);
  };
  const auto next = [&](std::size_t from) {
    for (std::size_t p = from; p < bytes.size(); ++p)
      if (header_at(p)) return p;
    return std::string_view::npos;
  };
  Salvage s;
  auto& [offsets, losses, truncated, truncated_at] = s;
  while (at < bytes.size()) {
    const bool header = header_at(at);
    const std::uint32_t size = header ? load_le32(bytes.data() + at + 4) : 0;
    const bool cut = !header ? bytes.size() - at < kRecordFrameHeaderBytes
                             : size > bytes.size() - at - kRecordFrameHeaderBytes;
    RecordEntry entry;
    if (header && !cut &&
        load_le32(bytes.data() + at + 8) == util::crc32c(bytes.data() + at + 16, size) &&
        entry.ParseFromArray(bytes.data() + at + 16, static_cast<int>(size))) {
      offsets.push_back(at);
      at += kRecordFrameHeaderBytes + size;
      continue;
    }
    const std::size_t n = next(at + 1);
    if (cut && n == std::string_view::npos) {
      truncated = true, truncated_at = at;
      break;
    }
    const std::uint64_t end = n == std::string_view::npos ? bytes.size() : n;
    if (!losses.empty() && losses.back().second == at)
      losses.back().second = end;
    else
      losses.emplace_back(at, end);
    if (n == std::string_view::npos) break;
    at = n;
  }
  return s;
}

TEST(FrameScan, RandomDamageIsSalvagedAsTheReaderBeforeDid) {
  std::string clean(record_preamble());
  append_record_frame(header_entry(), clean);
  for (int k = 0; k < 400; ++k) append_record_frame(step_entry(k), clean);
  std::mt19937 random(64);
  for (int copy = 0; copy < 200; ++copy) {
    std::string bytes = clean;
    const std::size_t flips = 1 + random() % 20;
    for (std::size_t i = 0; i < flips; ++i)
      bytes[8 + random() % (bytes.size() - 8)] ^= static_cast<char>(1u << (random() % 8));
    if (copy % 3 == 0) {  // a few crafted headers, some claiming sizes past the end
      std::string fake;
      for (int h = 0; h < 8; ++h)
        append_header(fake, static_cast<std::uint32_t>(random() % 40000), random());
      bytes.insert(8 + random() % (bytes.size() - 8), fake);
    }
    if (copy % 4 == 1) bytes.resize(8 + random() % (bytes.size() - 8));
    const RecordContents read = parse_record(bytes, "damaged.rthsrec");
    EXPECT_EQ(salvage_of(read), reference_salvage(bytes, kRecordPreambleBytes)) << "copy " << copy;
    EXPECT_LE(read.examined_bytes, 16 * bytes.size()) << "copy " << copy;
  }
}

// The same on the crafted headers, a few kB of them (the reference is quadratic).
TEST(FrameScan, CraftedHeadersAreSalvagedAsTheReaderBeforeDid) {
  for (Claim claim : {Claim::kToTheEnd, Claim::kToAnother}) {
    const std::string bytes = crafted_record(512, claim, 20);
    EXPECT_EQ(salvage_of(parse_record(bytes, "crafted.rthsrec")),
              reference_salvage(bytes, kRecordPreambleBytes));
  }
}

}  // namespace
}  // namespace rths::runtime
