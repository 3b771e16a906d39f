#include "study/study_inputs.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <limits>

#include <unistd.h>

#include "tests/support/chain_study.h"

namespace rths::study {
namespace {

namespace fs = std::filesystem;
const fs::path kConfigs = fs::path(RTHS_SOURCE_DIR) / "configs";

// An empty folder, so that a study that still named a file relative to it would fail to load.
fs::path empty_folder() {
  const fs::path dir = fs::temp_directory_path() / ("rths_inputs_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

PreparedStudy prepared_paper_frame_with_trace(const fs::path& trace_file) {
  std::ofstream(trace_file) << "# time s, delay s\n0, 0.010\n1.0, 0.012\n2.0, 0.011\n";
  config::Study study = load_study(kConfigs / "paper_frame.textproto");
  study.mutable_motion()->set_duration(3.0);
  config::Case& lagged = *study.mutable_cases(1);
  lagged.clear_delay();
  lagged.add_delay()->mutable_trace()->set_path(trace_file.string());
  return prepare_study(study, kConfigs);
}

TEST(StudyInputs, ARunFromTheEmbeddedStudyEqualsTheRunFromTheFilesBitForBit) {
  const fs::path elsewhere = empty_folder();
  const PreparedStudy from_files = prepared_paper_frame_with_trace(elsewhere / "trace.csv");
  const core::SimulationResult a =
      core::simulate(setup_for_case(from_files, from_files.config.cases(1)), from_files.motion);
  const config::Study embedded = with_embedded_inputs(from_files);
  fs::remove(elsewhere / "trace.csv");  // nothing left to read

  const PreparedStudy from_record = prepare_study(embedded, elsewhere);
  ASSERT_EQ(from_record.motion.acceleration, from_files.motion.acceleration);
  const config::Case& lagged = embedded.cases(1);
  const core::SimulationResult b =
      core::simulate(setup_for_case(from_record, lagged), from_record.motion);
  EXPECT_EQ(a.displacement, b.displacement);
  EXPECT_EQ(a.measured_force, b.measured_force);
  EXPECT_EQ(inputs_source(embedded, elsewhere), "embedded in the record");
  fs::remove_all(elsewhere);
}

TEST(StudyInputs, TheMotionIsEmbeddedAsRunWithItsSourceChecksum) {
  const config::Study study = load_study(kConfigs / "paper_frame.textproto");
  const PreparedStudy prepared = prepare_study(study, kConfigs);
  const config::Study embedded = with_embedded_inputs(prepared);
  const config::EmbeddedMotion& motion = embedded.motion().embedded();
  EXPECT_DOUBLE_EQ(motion.dt(), prepared.base.dt);
  EXPECT_EQ(static_cast<std::size_t>(motion.acceleration_size()),
            prepared.motion.acceleration.size());
  // data/SHA256SUMS's checksum of the paper's record.
  EXPECT_EQ(motion.source_sha256(),
            "fa44c724e6aea52f3b8837bb0e30ea36502f714faed69ba0413a21352582b1a6");
  EXPECT_TRUE(fs::path(embedded.motion().path()).is_absolute());
}

TEST(StudyInputs, MatrixFilesBecomeTheValuesRead) {
  const fs::path folder = kConfigs / "benchmark";
  const config::Study study = load_study(folder / "case_1.textproto");
  const PreparedStudy prepared = prepare_study(study, folder);
  const config::Study embedded = with_embedded_inputs(prepared);
  const config::MatrixStructure& m = embedded.structure().matrices();
  EXPECT_TRUE(m.mass().file().empty());
  EXPECT_EQ(m.stiffness().rows(), 3);
  EXPECT_EQ(m.stiffness().values_size(), 9);
  EXPECT_FALSE(m.has_influence());
  const fs::path elsewhere = empty_folder();
  const core::HybridSetup again = base_setup(embedded, prepared.base.dt, elsewhere);
  EXPECT_EQ(again.model.mass, prepared.base.model.mass);
  EXPECT_EQ(again.model.stiffness, prepared.base.model.stiffness);
  EXPECT_EQ(again.model.damping, prepared.base.model.damping);
  fs::remove_all(elsewhere);
}

// What a record of a lab-sized model embeds is O(nnz): the dense form held 2 n^2 doubles (1 MB
// at 250 DOFs, 1.6 GB at 10,000), a tridiagonal model's triplets about 9 bytes a nonzero.
TEST(StudyInputs, AModelReadSparseIsEmbeddedSparseAndReadBackBitForBit) {
  const int n = 250;
  const fs::path folder = empty_folder();
  const PreparedStudy prepared = prepare_study(test::chain_study(n, folder), folder);
  const config::Study embedded = with_embedded_inputs(prepared);
  const config::MatrixStructure& m = embedded.structure().matrices();
  ASSERT_TRUE(m.mass().has_sparse());
  ASSERT_TRUE(m.stiffness().has_sparse());
  EXPECT_EQ(m.stiffness().values_size(), 0);
  const core::SparseMat& k = prepared.base.model.sparse_stiffness;
  const Eigen::Index nonzeros = prepared.base.model.sparse_mass.nonZeros() + k.nonZeros();
  ASSERT_EQ(nonzeros, n + 3 * n - 2);
  EXPECT_LE(static_cast<double>(m.ByteSizeLong()) / static_cast<double>(nonzeros), 12.0)
      << m.ByteSizeLong() << " bytes for " << nonzeros << " nonzeros";

  const fs::path elsewhere = empty_folder();  // the files gone: the record alone
  const PreparedStudy again = prepare_study(embedded, elsewhere);
  const core::StructuralModel& a = prepared.base.model;
  const core::StructuralModel& b = again.base.model;
  EXPECT_EQ(core::Mat(b.sparse_mass), core::Mat(a.sparse_mass));
  EXPECT_EQ(core::Mat(b.sparse_stiffness), core::Mat(a.sparse_stiffness));
  EXPECT_EQ(b.sparse_stiffness.nonZeros(), k.nonZeros());
  EXPECT_EQ(b.stiffness, a.stiffness);
  EXPECT_EQ(b.damping, a.damping);
  fs::remove_all(elsewhere);
}

TEST(StudyInputs, AnOlderRecordSaysWhichFilesItFallsBackTo) {
  const config::Study study = load_study(kConfigs / "paper_frame.textproto");
  const std::string text = inputs_source(study, kConfigs);
  EXPECT_NE(text.find("older than embedded inputs"), std::string::npos) << text;
  EXPECT_NE(text.find("RSN175_IMPVALL.H_H-E12140.AT2"), std::string::npos) << text;
}

TEST(StudyInputs, AnAlteredMotionFileIsNamedWithItsExpectedChecksum) {
  config::GroundMotion motion = load_study(kConfigs / "paper_frame.textproto").motion();
  motion.set_sha256(std::string(64, '0'));
  try {
    (void)load_motion(motion, kConfigs);
    FAIL() << "an altered file was read";
  } catch (const std::invalid_argument& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("expected " + std::string(64, '0')), std::string::npos) << what;
    EXPECT_NE(what.find("fa44c724e6aea52f"), std::string::npos) << what;
  }
}

TEST(StudyInputs, ABrokenEmbeddedMotionIsNamed) {
  config::GroundMotion motion;
  motion.mutable_embedded()->set_dt(0.01);
  motion.mutable_embedded()->add_acceleration(std::numeric_limits<double>::quiet_NaN());
  EXPECT_THROW((void)load_motion(motion, {}), std::invalid_argument);
  motion.mutable_embedded()->set_acceleration(0, 1.0);
  motion.mutable_embedded()->set_dt(0.0);
  EXPECT_THROW((void)load_motion(motion, {}), std::invalid_argument);
}

}  // namespace
}  // namespace rths::study
