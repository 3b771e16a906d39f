// The memory a run keeps, checked before it is allocated (study/memory_budget.h), and a motion
// file too large to be a record refused by its size, both named instead of std::bad_alloc.
#include "study/memory_budget.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdlib>
#include <fstream>
#include <functional>

#include "study/study.h"

namespace rths::core {
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
  explicit MemoryLimit(const char* bytes) { ::setenv("RTHS_MEMORY_LIMIT", bytes, 1); }
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

TEST(MemoryBudget, AMotionFileFarBeyondAnyRecordIsRefusedByItsSize) {
  const auto dir =
      std::filesystem::temp_directory_path() / ("rths_memory_budget_" + std::to_string(getpid()));
  std::filesystem::create_directories(dir);
  const auto huge = dir / "huge.AT2";
  std::ofstream(huge) << "x";
  std::filesystem::resize_file(huge, 300ull << 20);  // sparse: costs no disk
  config::Study study = load_study(kConfigs / "paper_frame.textproto");
  study.mutable_motion()->set_path(huge.string());
  EXPECT_THAT(refusal([&] { prepare_study(study, kConfigs); }),
              HasSubstr("314572800 bytes, more than the 268435456 a motion file may have"));
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace rths::core
