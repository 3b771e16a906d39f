#pragma once
// What the view's tests share: the paper frame's lag_shift_14ms run in lockstep, in process,
// recorded at `record`, read back and removed from disk.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "runtime/record/record.h"
#include "tests/support/in_process_run.h"

namespace rths::test {

inline runtime::RecordContents recorded_paper_frame(const study::PreparedStudy& prepared,
                                                    const std::string& run_id,
                                                    const std::filesystem::path& record) {
  coordinator::CoordinatorOptions options;
  options.run_id = run_id;
  options.case_name = "lag_shift_14ms";
  options.record = record;
  const auto outcome = coordinator::run_in_process(prepared, options);
  EXPECT_TRUE(outcome.ok) << outcome.status;
  runtime::RecordContents contents = runtime::read_record(options.record);
  std::filesystem::remove(options.record);
  return contents;
}

}  // namespace rths::test
