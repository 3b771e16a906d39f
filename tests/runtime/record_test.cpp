#include "runtime/record/record.h"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <iterator>
#include <map>
#include <random>
#include <string_view>
#include <thread>

#include "runtime/record/record_checks.h"
#include "test_support.h"
#include "tests/support/in_process_run.h"
#include "util/crc32c.h"

namespace rths::runtime {
namespace {

constexpr int kSteps = 50;

std::filesystem::path temp_record(const std::string& name) {
  return std::filesystem::temp_directory_path() /
         ("rths_record_" + name + "_" + std::to_string(getpid()) + ".rthsrec");
}

void write_run(const std::filesystem::path& path, bool with_footer) {
  RecordWriter writer(path);
  RecordEntry header;
  header.mutable_header()->set_run_id("r1");
  header.mutable_header()->set_dofs(1);
  writer.write(header);
  for (int k = 0; k < kSteps; ++k) {
    RecordEntry step;
    step.mutable_step()->set_step(k);
    step.mutable_step()->add_displacement(0.001 * k);
    writer.write(step);
  }
  if (with_footer) {
    RecordEntry footer;
    footer.mutable_footer()->set_ok(true);
    writer.write(footer);
  }
}

TEST(Record, RoundTripsEveryEntry) {
  const auto path = temp_record("round_trip");
  write_run(path, true);
  const RecordContents contents = read_record(path);
  EXPECT_FALSE(contents.truncated);
  ASSERT_NE(contents.header(), nullptr);
  EXPECT_EQ(contents.header()->run_id(), "r1");
  ASSERT_EQ(contents.steps().size(), static_cast<std::size_t>(kSteps));
  EXPECT_EQ(contents.steps()[7]->displacement(0), 0.007);
  ASSERT_NE(contents.footer(), nullptr);
  EXPECT_TRUE(contents.footer()->ok());
}

TEST(Record, EachEntryIsOnDiskAsSoonAsItIsWritten) {
  const auto path = temp_record("flushed");
  RecordWriter writer(path);
  RecordEntry step;
  step.mutable_step()->set_step(3);
  writer.write(step);
  // Read while the writer is still open: nothing is held back in a user-space buffer.
  EXPECT_EQ(read_record(path).steps().size(), 1u);
}

TEST(Record, TruncatedFileReadsUpToTheLastCompleteEntryAndSaysSo) {
  const auto path = temp_record("truncated");
  write_run(path, false);
  const auto full = std::filesystem::file_size(path);
  std::filesystem::resize_file(path, full - 3);  // cut inside the last step
  const RecordContents contents = read_record(path);
  EXPECT_TRUE(contents.truncated);
  EXPECT_EQ(contents.steps().size(), static_cast<std::size_t>(kSteps - 1));
  EXPECT_NE(contents.warning.find("truncated"), std::string::npos);
  EXPECT_NE(contents.warning.find(path.string()), std::string::npos);
  EXPECT_EQ(contents.footer(), nullptr);
}

TEST(Record, MissingFileIsAnErrorNamingIt) {
  EXPECT_THROW(
      {
        try {
          read_record("/nonexistent/run.rthsrec");
        } catch (const std::runtime_error& e) {
          EXPECT_NE(std::string(e.what()).find("/nonexistent/run.rthsrec"), std::string::npos);
          throw;
        }
      },
      std::runtime_error);
}

TEST(Record, BytesThatAreNoRecordAreAnErrorNotAnEmptyRecord) {
  const auto path = temp_record("corrupt");
  {
    std::ofstream out(path, std::ios::binary);
    out << '\x04' << "\xff\xff\xff\xff";  // no preamble, no frame, no unchecksummed header
  }
  EXPECT_THROW(read_record(path), std::runtime_error);
}

std::string bytes_of(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

// The frame offsets of write_run's entries: header, its copy (before the first step), steps
// 0..kSteps-1, footer.
std::vector<std::size_t> frame_offsets(const std::string& bytes) {
  std::vector<std::size_t> out;
  for (std::size_t at = kRecordPreambleBytes; at < bytes.size();) {
    out.push_back(at);
    std::uint32_t size = 0;
    for (int i = 3; i >= 0; --i) size = (size << 8) | static_cast<std::uint8_t>(bytes[at + 4 + i]);
    at += kRecordFrameHeaderBytes + size;
  }
  return out;
}

TEST(Record, StartsWithItsPreambleAndFramesEachEntryWithItsChecksums) {
  const auto path = temp_record("framed");
  write_run(path, true);
  const std::string bytes = bytes_of(path);
  EXPECT_EQ(bytes.substr(0, kRecordPreambleBytes), std::string(record_preamble()));
  EXPECT_EQ(frame_offsets(bytes).size(), static_cast<std::size_t>(kSteps + 3));
  const RecordContents contents = parse_record(bytes, "mem");
  EXPECT_TRUE(contents.checksummed);
  EXPECT_FALSE(contents.lost_entries());
  EXPECT_TRUE(contents.warning.empty()) << contents.warning;
  const auto frames = frame_offsets(bytes);
  EXPECT_EQ(contents.offsets, std::vector<std::uint64_t>(frames.begin(), frames.end()));
}

// Every single byte of a step's frame, flipped alone: that step is reported lost by number and
// every other entry comes back intact.
TEST(Record, AFlippedByteLosesOnlyItsEntryAndTheReportNamesTheStep) {
  const auto path = temp_record("flip");
  write_run(path, true);
  const std::string good = bytes_of(path);
  const auto frames = frame_offsets(good);
  const int victim = 20;  // step 20: frame 22 (after the header and its copy)
  for (std::size_t at = frames[victim + 2]; at < frames[victim + 3]; ++at) {
    std::string bytes = good;
    bytes[at] = static_cast<char>(bytes[at] ^ 0x5A);
    const RecordContents contents = parse_record(bytes, "mem");
    SCOPED_TRACE("byte " + std::to_string(at));
    ASSERT_EQ(contents.losses.size(), 1u);
    EXPECT_EQ(contents.losses[0].first_byte, frames[victim + 2]);
    EXPECT_EQ(contents.losses[0].last_step_before, victim - 1);
    EXPECT_EQ(contents.losses[0].first_step_after, victim + 1);
    EXPECT_NE(contents.warning.find("step 20 lost"), std::string::npos) << contents.warning;
    EXPECT_EQ(contents.steps().size(), static_cast<std::size_t>(kSteps - 1));
    EXPECT_EQ(contents.missing_steps(),
              (std::vector<std::pair<std::int64_t, std::int64_t>>{{20, 20}}));
    ASSERT_NE(contents.header(), nullptr);
    ASSERT_NE(contents.footer(), nullptr);
    EXPECT_FALSE(contents.truncated);
  }
}

// The first header damaged: its copy before step 0 reads, so the record keeps its header.
TEST(Record, ADamagedHeaderOrFooterIsALossNotATruncation) {
  const auto path = temp_record("ends");
  write_run(path, true);
  const std::string good = bytes_of(path);
  const auto frames = frame_offsets(good);
  std::string bytes = good;
  bytes[frames.front() + 2] ^= 1;  // the header's sync
  bytes[frames.back() + 5] ^= 1;   // the footer's size
  const RecordContents contents = parse_record(bytes, "mem");
  ASSERT_NE(contents.header(), nullptr);
  EXPECT_EQ(contents.offsets.front(), frames[1]) << "the copy";
  EXPECT_EQ(contents.header()->run_id(), "r1");
  EXPECT_TRUE(contents.assumed.empty());
  EXPECT_EQ(contents.footer(), nullptr);
  EXPECT_FALSE(contents.truncated);
  ASSERT_EQ(contents.losses.size(), 2u);
  EXPECT_NE(contents.losses[0].describe().find("before step 0"), std::string::npos);
  EXPECT_NE(contents.losses[1].describe().find("after step 49"), std::string::npos);
  EXPECT_EQ(contents.steps().size(), static_cast<std::size_t>(kSteps));
}

TEST(Record, ADamagedPreambleIsReportedAndEveryEntryStillReads) {
  const auto path = temp_record("preamble");
  write_run(path, true);
  std::string bytes = bytes_of(path);
  bytes[3] = 'x';
  const RecordContents contents = parse_record(bytes, "mem");
  ASSERT_EQ(contents.losses.size(), 1u);
  EXPECT_EQ(contents.losses[0].end_byte, kRecordPreambleBytes);
  EXPECT_EQ(contents.steps().size(), static_cast<std::size_t>(kSteps));
  EXPECT_TRUE(contents.checksummed);
}

// A crash cuts the file anywhere: every cut inside an entry reads as a truncation of intact
// entries, never as damage; a cut between entries is a shorter record.
TEST(Record, EveryCutIsATruncationOfIntactEntries) {
  const auto path = temp_record("cuts");
  write_run(path, false);
  const std::string good = bytes_of(path);
  const auto frames = frame_offsets(good);
  for (std::size_t size = 0; size < good.size(); ++size) {
    const RecordContents contents = parse_record(good.substr(0, size), "mem");
    SCOPED_TRACE("cut at " + std::to_string(size));
    const auto whole = static_cast<std::size_t>(
        std::upper_bound(frames.begin(), frames.end(), size) - frames.begin());
    const bool between = std::find(frames.begin(), frames.end(), size) != frames.end();
    EXPECT_EQ(contents.truncated, !between);
    EXPECT_FALSE(contents.lost_entries()) << contents.warning;
    EXPECT_EQ(contents.entries.size(),
              size < kRecordPreambleBytes ? 0 : whole - 1);  // all but the cut one
  }
}

// A real record: the paper frame for 6 s (6000 steps, its header 8 times), run in process by the
// coordinator as `rths launch` runs it, under a displacement limit the response stays within.
const std::string& real_record() {
  static const std::string bytes = [] {
    const auto path = temp_record("real");
    coordinator::CoordinatorOptions options;
    options.run_id = "real";
    options.case_name = "reference";
    options.record = path;
    const auto outcome =
        coordinator::run_in_process(test::prepare(test::paper_frame_study(
                                        6, "deployment { limits { max_displacement: 0.5 } }")),
                                    options);
    EXPECT_TRUE(outcome.ok) << outcome.status;
    return bytes_of(path);
  }();
  return bytes;
}

// How a damaged copy of a record reads against the original: each entry whose bytes are all
// there unchanged must come back; each changed or cut one must not be read, and must lie in a
// named damaged region (or be the truncated tail).
struct Salvage {
  std::size_t intact_steps = 0, exported_steps = 0, damaged = 0, silent = 0, assumed = 0;
  bool exportable = true;  // a header (read or assumed) sizes the table as the original's does
  Salvage& operator+=(const Salvage& o) {
    intact_steps += o.intact_steps, exported_steps += o.exported_steps, damaged += o.damaged;
    silent += o.silent, assumed += o.assumed, exportable = exportable && o.exportable;
    return *this;
  }
};

bool named(const RecordContents& read, std::uint64_t first, std::uint64_t end, std::size_t size) {
  if (end > size && read.truncated && read.truncated_at <= first) return true;
  for (const RecordLoss& loss : read.losses)
    if (loss.first_byte <= first && std::min<std::uint64_t>(end, size) <= loss.end_byte)
      return true;
  return false;
}

Salvage salvage(const std::string& original, const std::string& damaged) {
  const RecordContents truth = parse_record(original, "original");
  const RecordContents read = parse_record(damaged, "damaged");
  std::map<std::uint64_t, std::size_t> read_at;
  for (std::size_t j = 0; j < read.offsets.size(); ++j) read_at[read.offsets[j]] = j;
  Salvage v;
  for (std::size_t i = 0; i < truth.offsets.size(); ++i) {
    const std::uint64_t first = truth.offsets[i];
    const std::uint64_t end = i + 1 < truth.offsets.size() ? truth.offsets[i + 1] : original.size();
    const bool intact = end <= damaged.size() &&
                        original.compare(first, end - first, damaged, first, end - first) == 0;
    const auto found = read_at.find(first);
    const bool back = found != read_at.end() && read.entries[found->second].SerializeAsString() ==
                                                    truth.entries[i].SerializeAsString();
    if (intact) {
      v.intact_steps += truth.entries[i].has_step();
      v.exported_steps += truth.entries[i].has_step() && back;
    } else if (first < damaged.size()) {
      ++v.damaged;
      v.silent += found != read_at.end() || !named(read, first, end, damaged.size());
    }
  }
  const RunHeader* h = read.header_or_assumed();
  v.exportable = read.steps().empty() ||
                 (h && h->dofs() == truth.header()->dofs() &&
                  h->actuators() == truth.header()->actuators() && !check_record(read).fatal);
  v.assumed = read.assumed.empty() ? 0 : 1;
  return v;
}

// The first header's frame: [offsets[0], offsets[1]).
std::pair<std::size_t, std::size_t> first_header(const std::string& record) {
  const RecordContents contents = parse_record(record, "real");
  return {contents.offsets[0], contents.offsets[1]};
}

TEST(RecordFaults, ARealRecordIsSoundAndRepeatsItsHeader) {
  const RecordContents contents = parse_record(real_record(), "real");
  EXPECT_TRUE(contents.warning.empty()) << contents.warning;
  EXPECT_EQ(contents.steps().size(), 6000u);
  std::size_t headers = 0;
  for (const RecordEntry& e : contents.entries) headers += e.has_header();
  EXPECT_EQ(headers, 8u) << "first, before steps 0, 1000, ..., 5000, before the footer";
  EXPECT_NE(contents.inputs_crc32c, 0u);
  EXPECT_EQ(contents.header()->inputs_crc32c(), contents.inputs_crc32c) << "names its inputs";
  const RecordChecks checks = check_record(contents);
  EXPECT_TRUE(checks.ok()) << checks.summary();
}

// The attack's trial: 200 copies with 1-100 random byte flips each and one byte of the first
// header flipped too: every intact step is read, every damaged entry is in a named region.
TEST(RecordFaults, FlippedCopiesWithTheirHeaderHitLoseNoIntactStepAndNothingSilently) {
  const std::string& original = real_record();
  const auto [header_at, header_end] = first_header(original);
  std::mt19937 random(51);
  Salvage total;
  for (int r = 0; r < 200; ++r) {
    std::string damaged = original;
    damaged[header_at + random() % (header_end - header_at)] ^=
        static_cast<char>(1 + random() % 255);
    for (int flips = 1 + static_cast<int>(random() % 100); flips > 0; --flips)
      damaged[random() % damaged.size()] ^= static_cast<char>(1 + random() % 255);
    const Salvage v = salvage(original, damaged);
    EXPECT_EQ(v.exported_steps, v.intact_steps) << "copy " << r;
    EXPECT_EQ(v.silent, 0u) << "copy " << r;
    EXPECT_TRUE(v.exportable) << "copy " << r;
    total += v;
  }
  EXPECT_GT(total.damaged, 2000u);
  std::cout << "200 flipped copies: " << total.damaged << " damaged entries, all named (0 silent); "
            << total.exported_steps << " of " << total.intact_steps << " intact steps read; "
            << total.assumed << " read with an assumed header\n";
}

// 60 cuts anywhere, each with one byte of the first header flipped: the header's copy before the
// first step (or, for a cut before it, nothing to lose) keeps every intact step readable.
TEST(RecordFaults, CutCopiesWithTheirHeaderHitLoseNoIntactStep) {
  const std::string& original = real_record();
  const auto [header_at, header_end] = first_header(original);
  std::mt19937 random(5151);
  Salvage total;
  for (int r = 0; r < 60; ++r) {
    std::string damaged =
        original.substr(0, header_end + random() % (original.size() - header_end));
    damaged[header_at + random() % (header_end - header_at)] ^=
        static_cast<char>(1 + random() % 255);
    const Salvage v = salvage(original, damaged);
    EXPECT_EQ(v.exported_steps, v.intact_steps) << "cut " << r << " at " << damaged.size();
    EXPECT_EQ(v.silent, 0u) << "cut " << r;
    EXPECT_TRUE(v.exportable) << "cut " << r;
    EXPECT_EQ(v.assumed, 0u) << "cut " << r << ": the copy before step 0 reads";
    total += v;
  }
  std::cout << "60 cuts: " << total.exported_steps << " of " << total.intact_steps
            << " intact steps read, " << total.silent << " silent\n";
}

// Every header copy damaged: the steps are still read, with the header they imply, named.
TEST(RecordFaults, EveryHeaderCopyDamagedStillReadsTheStepsWithAnAssumedHeader) {
  std::string damaged = real_record();
  const RecordContents truth = parse_record(damaged, "real");
  for (std::size_t i = 0; i < truth.entries.size(); ++i)
    if (truth.entries[i].has_header()) damaged[truth.offsets[i] + kRecordFrameHeaderBytes + 3] ^= 1;
  const RecordContents read = parse_record(damaged, "real");
  EXPECT_EQ(read.header(), nullptr);
  ASSERT_NE(read.header_or_assumed(), nullptr);
  EXPECT_EQ(read.steps().size(), 6000u);
  EXPECT_EQ(read.header_or_assumed()->dofs(), truth.header()->dofs());
  EXPECT_EQ(read.header_or_assumed()->actuators(), truth.header()->actuators());
  EXPECT_NEAR(read.header_or_assumed()->dt(), truth.header()->dt(), 1e-12);
  EXPECT_EQ(read.header_or_assumed()->link_node_ids_size(), truth.header()->link_node_ids_size());
  EXPECT_NE(read.warning.find("no intact header (every copy damaged or missing): read with one "
                              "assumed from the steps: dofs 1 and actuators 1"),
            std::string::npos)
      << read.warning;
}

// A 16-byte frame header whose own checksum holds, claiming `size` payload bytes.
std::string fake_frame(std::uint32_t size) {
  std::string frame("\xF3\x7A\x1C\xB5", 4);
  for (std::uint32_t v : {size, 0u})
    for (int i = 0; i < 4; ++i) frame.push_back(static_cast<char>((v >> (8 * i)) & 0xFFu));
  const std::uint32_t crc = util::crc32c(frame.data(), 12);
  for (int i = 0; i < 4; ++i) frame.push_back(static_cast<char>((crc >> (8 * i)) & 0xFFu));
  return frame;
}

// A forged frame in the middle claiming 4 GB (more than the file), or 100 kB (within it, payload
// checksum false): a damaged region of its 16 bytes; every step after it is read.
TEST(RecordFaults, AFrameWithAnImpossibleSizeHidesNoStepAfterIt) {
  const std::string& original = real_record();
  const RecordContents truth = parse_record(original, "real");
  const std::size_t at = truth.offsets[truth.offsets.size() / 2];
  for (std::uint32_t size : {0xFFFFFFF0u, 100000u}) {
    SCOPED_TRACE("claimed size " + std::to_string(size));
    const std::string forged = original.substr(0, at) + fake_frame(size) + original.substr(at);
    const RecordContents read = parse_record(forged, "forged");
    EXPECT_FALSE(read.truncated) << read.warning;
    EXPECT_EQ(read.steps().size(), truth.steps().size());
    ASSERT_NE(read.footer(), nullptr);
    ASSERT_EQ(read.losses.size(), 1u);
    EXPECT_EQ(read.losses[0].first_byte, at);
    EXPECT_EQ(read.losses[0].end_byte, at + kRecordFrameHeaderBytes);
  }
}

// A record from before checksums: varint size, then the entry.
TEST(Record, AnOldRecordWithoutChecksumsStillReadsWithAWarning) {
  std::string bytes;
  for (int k = -1; k < 3; ++k) {
    RecordEntry e;
    if (k < 0)
      e.mutable_header()->set_run_id("old");
    else
      e.mutable_step()->set_step(k);
    const std::string payload = e.SerializeAsString();
    bytes.push_back(static_cast<char>(payload.size()));  // < 128: a one-byte varint
    bytes += payload;
  }
  const RecordContents contents = parse_record(bytes, "old.rthsrec");
  EXPECT_FALSE(contents.checksummed);
  ASSERT_NE(contents.header(), nullptr);
  EXPECT_EQ(contents.header()->run_id(), "old");
  EXPECT_EQ(contents.steps().size(), 3u);
  EXPECT_NE(contents.warning.find("without checksums"), std::string::npos) << contents.warning;
  EXPECT_NE(contents.warning.find("old.rthsrec"), std::string::npos);
}

RecordEntry step_entry(int k) {
  RecordEntry e;
  e.mutable_step()->set_step(k);
  e.mutable_step()->add_displacement(0.001 * k);
  return e;
}

TEST(AsyncRecord, WritesEveryEntryInOrder) {
  const auto path = temp_record("async");
  {
    AsyncRecordWriter writer(path, 8);
    for (int k = 0; k < 1000; ++k)
      while (!writer.append(step_entry(k))) std::this_thread::yield();  // test only: never drop
    writer.close();
    EXPECT_EQ(writer.written(), 1000u);
  }
  const RecordContents record = read_record(path);
  ASSERT_EQ(record.steps().size(), 1000u);
  for (int k = 0; k < 1000; ++k) {
    EXPECT_EQ(record.steps()[k]->step(), k);
    EXPECT_EQ(record.steps()[k]->displacement(0), 0.001 * k);
  }
  EXPECT_FALSE(record.truncated);
  std::filesystem::remove(path);
}

TEST(AsyncRecord, AFullQueueDropsAndCountsInsteadOfBlocking) {
  // The writer stalls on a pipe nobody reads (64 KiB of kernel buffer); the ring of 8 fills.
  const auto fifo = temp_record("fifo");
  std::filesystem::remove(fifo);
  ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);
  const int reader = open(fifo.c_str(), O_RDONLY | O_NONBLOCK);
  ASSERT_GE(reader, 0);
  std::uint64_t accepted = 0;
  {
    AsyncRecordWriter writer(fifo, 8);
    RecordEntry big;
    big.mutable_event()->set_what(std::string(4096, 'x'));
    const auto start = std::chrono::steady_clock::now();
    for (int i = 0; i < 200; ++i) accepted += writer.append(big) ? 1 : 0;
    // 200 appends of 4 KiB into a stalled writer took no time: append never waited.
    EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(2));
    EXPECT_GT(writer.dropped(), 0u);
    EXPECT_EQ(writer.dropped() + accepted, 200u);
    // Unblock the writer so that close() can finish.
    std::thread drain([reader] {
      char buffer[65536];
      for (;;) {
        const ssize_t n = read(reader, buffer, sizeof buffer);
        if (n == 0) return;  // writer closed
        if (n < 0) std::this_thread::sleep_for(std::chrono::milliseconds(1));
      }
    });
    writer.close();
    drain.join();
    EXPECT_EQ(writer.written(), accepted);
  }
  close(reader);
  std::filesystem::remove(fifo);
}

TEST(AsyncRecord, AFullDiskFailsTheWriterWhichSaysWhyAndNeverBlocks) {
  AsyncRecordWriter writer("/dev/full", 8);
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  for (int k = 0; !writer.failed() && std::chrono::steady_clock::now() < deadline; ++k) {
    writer.append(step_entry(k));
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  ASSERT_TRUE(writer.failed());
  EXPECT_NE(writer.failure().find("/dev/full"), std::string::npos) << writer.failure();
  EXPECT_NE(writer.failure().find(std::strerror(ENOSPC)), std::string::npos) << writer.failure();
  for (int k = 0; k < 100; ++k) writer.append(step_entry(k));  // drained, not blocked
  EXPECT_THROW(writer.close(), std::runtime_error);
}

// A file-size limit (RLIMIT_FSIZE, SIGXFSZ ignored: writes past it fail with EFBIG) in a child
// process: the writer fails at the limit and the file is a readable prefix of what was appended.
TEST(AsyncRecord, AWriteThatFailsLeavesAReadablePrefixAndNothingAfterIt) {
  constexpr rlim_t kLimit = 20000;
  const auto path = temp_record("fsize");
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    signal(SIGXFSZ, SIG_IGN);
    const rlimit limit{kLimit, kLimit};
    setrlimit(RLIMIT_FSIZE, &limit);
    AsyncRecordWriter writer(path, 16);
    for (int k = 0; k < 3000 && !writer.failed(); ++k) {
      while (!writer.append(step_entry(k))) {}
      std::this_thread::sleep_for(std::chrono::microseconds(50));
    }
    const bool failed =
        writer.failed() && writer.failure().find(std::strerror(EFBIG)) != std::string::npos;
    _exit(failed ? 0 : 1);
  }
  int status = 0;
  waitpid(child, &status, 0);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 0) << "the writer did not report EFBIG";
  EXPECT_EQ(std::filesystem::file_size(path), kLimit);
  const RecordContents record = read_record(path);
  EXPECT_TRUE(record.truncated);
  EXPECT_FALSE(record.lost_entries()) << record.warning;
  const auto steps = record.steps();
  EXPECT_GT(steps.size(), 500u);
  for (std::size_t k = 0; k < steps.size(); ++k) ASSERT_EQ(steps[k]->step(), static_cast<long>(k));
  std::filesystem::remove(path);
}

TEST(AsyncRecord, KillMinus9LosesAtMostTheQueuedEntriesAndLeavesAReadablePrefix) {
  constexpr std::size_t kCapacity = 16;
  constexpr int kAppended = 3000;
  const auto path = temp_record("crash");
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    AsyncRecordWriter writer(path, kCapacity);
    for (int k = 0; k < kAppended; ++k)
      while (!writer.append(step_entry(k))) {}
    raise(SIGKILL);  // the crash: no close(), no destructor
  }
  int status = 0;
  waitpid(child, &status, 0);
  ASSERT_TRUE(WIFSIGNALED(status));
  const RecordContents record = read_record(path);
  const auto steps = record.steps();
  EXPECT_GE(steps.size(), static_cast<std::size_t>(kAppended) - kCapacity);
  for (std::size_t k = 0; k < steps.size(); ++k) ASSERT_EQ(steps[k]->step(), static_cast<long>(k));
  std::filesystem::remove(path);
}

// The live view's seam: every entry, in order, as the file has it, on the writer's thread.
TEST(AsyncRecord, TheObserverSeesEachWrittenEntryOnTheWritersThread) {
  struct Seen : RecordObserver {
    std::string bytes;
    std::vector<std::thread::id> threads;
    void on_entry(std::string_view delimited) override {
      bytes.append(delimited);
      threads.push_back(std::this_thread::get_id());
    }
  } seen;
  const auto path = temp_record("observer");
  {
    AsyncRecordWriter writer(path, 8);
    writer.set_observer(&seen);
    for (int k = 0; k < kSteps; ++k) {
      RecordEntry step;
      step.mutable_step()->set_step(k);
      while (!writer.append(step)) std::this_thread::yield();
    }
    writer.close();
  }
  std::ifstream in(path, std::ios::binary);
  const std::string file((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  // The file is the preamble, then exactly the frames the observer saw.
  ASSERT_GE(file.size(), seen.bytes.size());
  EXPECT_EQ(file.substr(file.size() - seen.bytes.size()), seen.bytes);
  EXPECT_EQ(file.size() - seen.bytes.size(), kRecordPreambleBytes);
  ASSERT_EQ(seen.threads.size(), static_cast<std::size_t>(kSteps));
  for (const auto& id : seen.threads) EXPECT_NE(id, std::this_thread::get_id());
  std::filesystem::remove(path);
}

}  // namespace
}  // namespace rths::runtime
