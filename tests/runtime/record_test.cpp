#include "runtime/record.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

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

}  // namespace
}  // namespace rths::runtime
