// The memory a run keeps, checked before it is allocated (study/memory_budget.h), and a motion
// file larger than its reading may hold refused by its size before it is read
// (study/motion_files.h), both named instead of std::bad_alloc.
#include "study/memory_budget.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdlib>
#include <fstream>
#include <functional>
#include <limits>
#include <optional>

#include "core/number_text.h"
#include "study/motion_files.h"
#include "study/study.h"

namespace rths::study {
namespace {

using testing::HasSubstr;

const std::filesystem::path kConfigs = std::filesystem::path(RTHS_SOURCE_DIR) / "configs";

std::string refusal(const std::function<void()>& f) {
  try {
    f();
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "(accepted)";
}

// Sets RTHS_MEMORY_LIMIT for one test and clears it after.
struct MemoryLimit {
  explicit MemoryLimit(const char* bytes) {
    if (*bytes)
      ::setenv("RTHS_MEMORY_LIMIT", bytes, 1);
    else
      ::unsetenv("RTHS_MEMORY_LIMIT");
  }
  ~MemoryLimit() { ::unsetenv("RTHS_MEMORY_LIMIT"); }
};

TEST(MemoryBudget, ARunBeyondTheLimitIsRefusedNamingTheEstimateAndTheLimit) {
  const MemoryLimit limit("1048576");  // 1 MiB
  EXPECT_EQ(memory_limit_bytes(), 1048576u);
  EXPECT_NO_THROW(require_memory(1000, 1000, "small"));
  EXPECT_THAT(refusal([] { require_memory(2000, 1000, "this run"); }),
              testing::AllOf(HasSubstr("this run keeps 2000 rows x 1000 bytes = 1.9"),
                             HasSubstr("more than the memory limit of 1 MiB")));
  EXPECT_THAT(refusal([] { require_memory(~0ull / 2, 16, "overflowing"); }),
              HasSubstr("overflowing keeps"));
}

TEST(MemoryBudget, WithoutAnOverrideTheLimitIsAtMostHalfThisMachine) {
  ::unsetenv("RTHS_MEMORY_LIMIT");
  const std::uint64_t physical =
      static_cast<std::uint64_t>(sysconf(_SC_PHYS_PAGES)) * sysconf(_SC_PAGESIZE);
  EXPECT_GT(memory_limit_bytes(), 0u);
  EXPECT_LE(memory_limit_bytes(), physical / 2);
}

TEST(MemoryBudget, AMicrosecondStepOverTheRecordIsRefusedBeforeAnythingIsAllocated) {
  const MemoryLimit limit("1000000000");  // 1 GB
  config::Study study = load_study(kConfigs / "paper_frame.textproto");
  study.mutable_integrator()->set_dt(1e-6);
  EXPECT_THAT(refusal([&] { prepare_study(study, kConfigs); }),
              testing::AllOf(HasSubstr("integrator.dt = 1e-06 s over the"),
                             HasSubstr("more than the memory limit")));
}

// A fresh folder for one test's files, removed with it.
struct Scratch {
  explicit Scratch(const std::string& name)
      : dir(std::filesystem::temp_directory_path() /
            ("rths_memory_budget_" + name + "_" + std::to_string(getpid()))) {
    std::filesystem::create_directories(dir);
  }
  ~Scratch() { std::filesystem::remove_all(dir); }
  // A file of `bytes` holding "x" then zeros: sparse, so it costs no disk and no time to make,
  // and read, it would be refused as binary data, not by its size.
  std::filesystem::path sparse(const std::string& name, std::uintmax_t bytes) const {
    std::ofstream(dir / name) << "x";
    std::filesystem::resize_file(dir / name, bytes);
    return dir / name;
  }
  std::filesystem::path dir;
};

TEST(MemoryBudget, A255MiBMotionFileIsRefusedByItsSizeBeforeAByteOfItIsRead) {
  const Scratch scratch("motion_255");
  const auto huge = scratch.sparse("huge.AT2", 255ull << 20);
  config::Study study = load_study(kConfigs / "paper_frame.textproto");
  study.mutable_motion()->set_path(huge.string());
  for (const char* cap : {"4294967296", ""}) {  // a 4 GiB cap (82 MiB of file), none (128 MiB)
    const MemoryLimit limit(cap);
    const std::string limit_bytes = std::to_string(motion_file_limit_bytes());
    const std::string why = refusal([&] { prepare_study(study, kConfigs); });
    EXPECT_THAT(why, testing::AllOf(HasSubstr(huge.string()),
                                    HasSubstr("267386880 bytes (255.0 MiB), more than the " +
                                              limit_bytes + " bytes"),
                                    HasSubstr("refused before reading it")))
        << cap;
    EXPECT_THAT(why, testing::Not(HasSubstr("binary"))) << "the file was read: " << why;
    // Each reader sizes it itself, whoever calls it.
    EXPECT_THAT(refusal([&] { read_at2(huge); }), HasSubstr("267386880 bytes"));
    EXPECT_THAT(refusal([&] { read_columns(huge, 0.01, 1.0); }), HasSubstr("267386880 bytes"));
    EXPECT_THAT(refusal([&] { is_at2_file(huge); }), HasSubstr("267386880 bytes"));
  }
  {
    const MemoryLimit limit("4294967296");
    EXPECT_EQ(motion_file_limit_bytes(), 4294967296ull / kMotionReadBytesPerFileByte);
  }
  EXPECT_LE(motion_file_limit_bytes(), kMaxMotionFileBytes);
}

TEST(MemoryBudget, AMotionFileIsHeldToWhatTheMemoryLimitCanReadAndANormalOneStillReads) {
  const Scratch scratch("motion_budget");
  const auto motion = scratch.dir / "long.txt";
  {
    std::ofstream out(motion);
    for (int i = 0; i < 300000; ++i) out << (i % 7) * 0.001 << "\n";  // about 1.8 MiB
  }
  const auto bytes = std::filesystem::file_size(motion);
  {
    const MemoryLimit limit("52428800");  // 50 MiB: reading may take 1 MiB of file
    EXPECT_EQ(motion_file_limit_bytes(), 1048576u);
    EXPECT_THAT(refusal([&] { read_columns(motion, 0.01, 1.0); }),
                testing::AllOf(HasSubstr(std::to_string(bytes) + " bytes"),
                               HasSubstr("1048576 bytes (1.0 MiB)"),
                               HasSubstr("memory limit of 50.0 MiB")));
  }
  const MemoryLimit limit("1073741824");  // 1 GiB
  const core::GroundMotion read = read_columns(motion, 0.01, 1.0);
  EXPECT_EQ(read.acceleration.size(), 300000u);
  EXPECT_DOUBLE_EQ(read.acceleration[6], 0.006);
  const core::GroundMotion record = read_at2(std::filesystem::path(RTHS_DATA_DIR) /
                                             "ground_motions" / "elcentro_1940_ns_peknold.AT2");
  EXPECT_EQ(record.acceleration.size(), 1559u);
}

// The run is sized from the motion file's extent before a row of it is parsed: the file's last
// line is not a number, so a reader that parsed first would refuse it for that instead.
TEST(MemoryBudget, AMotionWhoseRunCannotFitIsRefusedByItsExtentBeforeARowIsParsed) {
  const Scratch scratch("motion_extent");
  const auto motion = scratch.dir / "long.txt";
  {
    std::ofstream out(motion);
    out << "# acceleration, g\n  acceleration\n\n";
    for (int i = 0; i < 200000; ++i) out << (i % 7) * 0.001 << "\n";
    out << "not-a-number\n";
  }
  const std::optional<MotionFileExtent> extent = motion_file_extent(motion, false, 0.001);
  ASSERT_TRUE(extent.has_value());
  EXPECT_EQ(extent->samples, 200001u);  // the title, 200,000 rows and the last line, less one
  EXPECT_FALSE(motion_file_extent(motion, false, 0.0).has_value());
  config::Study study = load_study(kConfigs / "paper_frame.textproto");
  study.mutable_motion()->set_path(motion.string());
  study.mutable_motion()->clear_sha256();
  study.mutable_motion()->set_column_dt(0.001);
  study.mutable_motion()->set_column_units(config::GroundMotion::G);
  const MemoryLimit limit("1000000000");  // 1 GB: 200 s at 1e-5 s holds 20 million rows
  study.mutable_integrator()->set_dt(1e-5);
  EXPECT_THAT(refusal([&] { prepare_study(study, kConfigs); }),
              testing::AllOf(HasSubstr("integrator.dt = 1e-05 s over the 200.001 s record (200001 "
                                       "samples by the motion file's extent"),
                             HasSubstr("more than the memory limit"),
                             testing::Not(HasSubstr("not-a-number"))));
  study.mutable_integrator()->set_dt(0.001);  // fits: the file is then read, and its line refused
  EXPECT_THAT(refusal([&] { prepare_study(study, kConfigs); }),
              HasSubstr("'not-a-number' is not a finite number"));
}

// A hostile column_dt is refused by name before it reaches a count of steps (a double past 2^64
// cast to uint64 is undefined behaviour).
TEST(MemoryBudget, AColumnDtWithoutAFiniteRecordIsRefusedNamingIt) {
  const Scratch scratch("hostile_column_dt");
  const auto motion = scratch.dir / "short.txt";
  {
    std::ofstream out(motion);
    for (int i = 0; i < 1000; ++i) out << (i % 7) * 0.001 << "\n";
  }
  config::Study study = load_study(kConfigs / "paper_frame.textproto");
  study.mutable_motion()->set_path(motion.string());
  study.mutable_motion()->clear_sha256();
  study.mutable_motion()->set_column_units(config::GroundMotion::G);
  study.mutable_integrator()->set_dt(0.0);
  for (const double hostile : {1e308, std::numeric_limits<double>::infinity(),
                               std::numeric_limits<double>::quiet_NaN(), -0.01}) {
    study.mutable_motion()->set_column_dt(hostile);
    EXPECT_THAT(refusal([&] { prepare_study(study, kConfigs); }),
                HasSubstr("motion.column_dt = " + core::format_number(hostile) + " s over"))
        << hostile;
  }
  // A finite record whose steps at dt overflow a count: 1e12 s x 999 samples at 1e-6 s.
  study.mutable_motion()->set_column_dt(1e12);
  study.mutable_integrator()->set_dt(1e-6);
  EXPECT_THAT(refusal([&] { prepare_study(study, kConfigs); }),
              testing::AllOf(HasSubstr("integrator.dt = 1e-06 s over the 9.99e+14 s record"),
                             HasSubstr("steps, not a count a run can keep")));
}

}  // namespace
}  // namespace rths::study
