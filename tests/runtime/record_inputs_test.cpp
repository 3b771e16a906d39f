// The inputs entry of a record of a lab-sized model, written as `rths launch` writes it (the
// coordinator, here in process): M and K read sparse go in as triplets, O(nnz), and the study read
// back from the record alone gives the same model, bit for bit.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>

#include "runtime/record/record.h"
#include "tests/support/chain_study.h"
#include "tests/support/in_process_run.h"

namespace rths::runtime {
namespace {

namespace fs = std::filesystem;

// Equal pattern and values (== on nonzero doubles: the same bits).
void expect_same(const core::SparseMat& read, const core::SparseMat& written) {
  EXPECT_EQ(read.nonZeros(), written.nonZeros());
  EXPECT_EQ(core::Mat(read), core::Mat(written));
}

TEST(RecordInputs, A2000DofChainIsCarriedSparseAndReadBackBitForBit) {
  const int n = 2000;
  const fs::path folder =
      fs::temp_directory_path() / ("rths_record_inputs_" + std::to_string(getpid()));
  fs::remove_all(folder);
  fs::create_directories(folder);
  const study::PreparedStudy prepared =
      study::prepare_study(test::chain_study(n, folder, 0.05), folder);
  coordinator::CoordinatorOptions options;
  options.run_id = "chain";
  options.case_name = "reference";
  options.record = folder / "chain.rthsrec";
  const coordinator::RunOutcome outcome = coordinator::run_in_process(prepared, options);
  ASSERT_TRUE(outcome.ok) << outcome.status;

  const RecordContents record = read_record(options.record);
  std::size_t inputs_bytes = 0;
  for (const RecordEntry& entry : record.entries)
    if (entry.has_inputs()) inputs_bytes = entry.ByteSizeLong();
  ASSERT_GT(inputs_bytes, 0u) << "no inputs entry";
  // Dense, M and K held 2 n^2 doubles: 64 MB, 8,000 bytes a nonzero.
  const double nonzeros = n + 3.0 * n - 2;
  EXPECT_LE(static_cast<double>(inputs_bytes) / nonzeros, 12.0) << inputs_bytes << " bytes";
  EXPECT_LE(static_cast<double>(fs::file_size(options.record)) / nonzeros, 40.0);

  fs::remove(folder / "mass.mtx");  // nothing left to read but the record
  fs::remove(folder / "stiffness.mtx");
  const config::Study* as_run = record.study_as_run();
  ASSERT_NE(as_run, nullptr);
  ASSERT_TRUE(as_run->structure().matrices().stiffness().has_sparse());
  const study::PreparedStudy again = study::prepare_study(*as_run, folder);
  const core::StructuralModel &a = prepared.base.model, &b = again.base.model;
  expect_same(b.sparse_mass, a.sparse_mass);
  expect_same(b.sparse_stiffness, a.sparse_stiffness);
  EXPECT_EQ(b.damping, a.damping);
  fs::remove_all(folder);
}

}  // namespace
}  // namespace rths::runtime
