#include "runtime/record.h"

#include <gtest/gtest.h>
#include <fcntl.h>
#include <signal.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <string_view>
#include <thread>

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

TEST(Record, CorruptEntryIsAnErrorNotSilentlySkipped) {
  const auto path = temp_record("corrupt");
  {
    std::ofstream out(path, std::ios::binary);
    out << '\x04' << "\xff\xff\xff\xff";  // a 4-byte entry that is not a RecordEntry
  }
  EXPECT_THROW(read_record(path), std::runtime_error);
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

TEST(AsyncRecord, KillMinus9LosesAtMostTheQueuedEntriesAndLeavesAReadablePrefix) {
  constexpr std::size_t kCapacity = 16;
  constexpr int kAppended = 3000;
  const auto path = temp_record("crash");
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    AsyncRecordWriter writer(path, kCapacity);
    for (int k = 0; k < kAppended; ++k)
      while (!writer.append(step_entry(k))) {
      }
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
  EXPECT_EQ(seen.bytes, file);
  ASSERT_EQ(seen.threads.size(), static_cast<std::size_t>(kSteps));
  for (const auto& id : seen.threads) EXPECT_NE(id, std::this_thread::get_id());
  std::filesystem::remove(path);
}

}  // namespace
}  // namespace rths::runtime
