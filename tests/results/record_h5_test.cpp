// results::RecordH5Writer: a record's steps in HDF5 as the run goes, read back with libhdf5: the
// columns of the recorded DOFs and actuators with their units, every step once the footer came,
// and a process killed mid-run (SIGKILL) leaves a file that reads with every block written before.
#include "results/record_h5.h"

#include <gtest/gtest.h>
#include <hdf5.h>
#include <sys/wait.h>
#include <unistd.h>

#include <csignal>
#include <filesystem>
#include <string>
#include <vector>

namespace rths::results {
namespace {

std::filesystem::path scratch(const std::string& name) {
  const auto dir = std::filesystem::temp_directory_path() /
                   ("rths_record_h5_" + name + "_" + std::to_string(getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

// The entry as the record's writer frames it (what RecordObserver::on_entry sees).
std::string frame(const runtime::RecordEntry& entry) {
  std::string bytes;
  runtime::append_record_frame(entry, bytes);
  return bytes;
}

// A 2,000-DOF run's header keeping DOFs 1 and 2000, one actuator.
runtime::RecordEntry header() {
  runtime::RecordEntry e;
  runtime::RunHeader& h = *e.mutable_header();
  h.set_dofs(2000);
  h.set_actuators(1);
  h.add_recorded_dofs(0);
  h.add_recorded_dofs(1999);
  return e;
}

// Step k: u = k mm at DOF 1, -k mm at DOF 2000; the force 10 k N.
runtime::RecordEntry step(int k) {
  runtime::RecordEntry e;
  runtime::StepRecord& s = *e.mutable_step();
  s.set_step(k);
  s.set_time(k / 1024.0);
  for (const double u : {1e-3 * k, -1e-3 * k}) {
    s.add_displacement(u);
    s.add_velocity(2 * u);
    s.add_acceleration(4 * u);
  }
  s.add_command(0.5e-3 * k);
  s.add_realised(0.4e-3 * k);
  s.add_measured_force(10.0 * k);
  s.set_overrun(k % 7 == 0);
  return e;
}

runtime::RecordEntry footer() {
  runtime::RecordEntry e;
  e.mutable_footer()->set_status("completed");
  return e;
}

// A dataset of the file, read with libhdf5 (empty when it cannot be read).
std::vector<double> column(const std::filesystem::path& path, const char* name) {
  std::vector<double> out;
  const hid_t file = H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  const hid_t dataset = H5Dopen2(file, name, H5P_DEFAULT);
  const hid_t space = H5Dget_space(dataset);
  hsize_t rows = 0;
  if (space >= 0 && H5Sget_simple_extent_dims(space, &rows, nullptr) == 1) {
    out.resize(rows);
    if (rows > 0 &&
        H5Dread(dataset, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, out.data()) < 0)
      out.clear();
  }
  H5Sclose(space);
  H5Dclose(dataset);
  H5Fclose(file);
  return out;
}

double complete(const std::filesystem::path& path) {
  double value = -1.0;
  const hid_t file = H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  const hid_t attr = H5Aopen(file, "complete", H5P_DEFAULT);
  H5Aread(attr, H5T_NATIVE_DOUBLE, &value);
  H5Aclose(attr);
  H5Fclose(file);
  return value;
}

TEST(RecordH5, EveryStepOfTheRecordedDofsReadsBackOnceTheFooterCame) {
  const auto path = scratch("whole") / "run.h5";
  {
    RecordH5Writer writer(path, 100);
    writer.on_entry(frame(header()));
    for (int k = 0; k < 250; ++k) writer.on_entry(frame(step(k)));
    EXPECT_EQ(writer.rows_written(), 200u);  // two blocks; 50 steps held
    writer.on_entry(frame(header()));        // the copy before the footer starts nothing over
    writer.on_entry(frame(footer()));
    writer.close();
    EXPECT_EQ(writer.rows_written(), 250u);
    EXPECT_EQ(writer.failure(), "");
  }
  const std::vector<double> u1 = column(path, "u_floor1_m"), u2000 = column(path, "u_floor2000_m");
  ASSERT_EQ(u1.size(), 250u);
  ASSERT_EQ(u2000.size(), 250u);
  EXPECT_DOUBLE_EQ(u1[249], 0.249);
  EXPECT_DOUBLE_EQ(u2000[123], -0.123);
  EXPECT_DOUBLE_EQ(column(path, "a_floor2000_m_per_s2")[10], -0.04);
  EXPECT_DOUBLE_EQ(column(path, "force_act1_N")[249], 2490.0);
  EXPECT_EQ(column(path, "step")[249], 249.0);
  EXPECT_EQ(column(path, "overrun")[14], 1.0);
  EXPECT_TRUE(column(path, "u_floor2_m").empty());
  EXPECT_EQ(complete(path), 1.0);
}

// The child writes 350 steps in blocks of 100 and is killed (SIGKILL) without closing: the file
// reads, with the three blocks it had written and `complete` still 0.
TEST(RecordH5, AProcessKilledMidRunLeavesTheBlocksItHadWritten) {
  const auto path = scratch("killed") / "run.h5";
  int ready[2];
  ASSERT_EQ(pipe(ready), 0);
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    RecordH5Writer writer(path, 100);
    writer.on_entry(frame(header()));
    for (int k = 0; k < 350; ++k) writer.on_entry(frame(step(k)));
    const char done = writer.rows_written() == 300 ? 'y' : 'n';
    (void)!write(ready[1], &done, 1);
    for (;;) pause();
  }
  char done = 0;
  ASSERT_EQ(read(ready[0], &done, 1), 1);
  kill(child, SIGKILL);
  int status = 0;
  waitpid(child, &status, 0);
  EXPECT_EQ(done, 'y');
  const std::vector<double> u1 = column(path, "u_floor1_m");
  ASSERT_EQ(u1.size(), 300u);
  EXPECT_DOUBLE_EQ(u1[299], 0.299);
  EXPECT_EQ(column(path, "force_act1_N").size(), 300u);
  EXPECT_EQ(complete(path), 0.0);
}

}  // namespace
}  // namespace rths::results
