#pragma once
// A run record's steps in HDF5, written as the run goes (rths-coordinator --h5 FILE, rths launch
// --format h5): a RecordObserver of the coordinator's record writer, so it runs on the record's
// writer thread, never on the loop's.
//
// Input: the record's entries as framed (RecordObserver::on_entry): the header (its first copy
// sets the columns), then the steps, then the footer.
// Output at `path`: one extendible 1-D float64 dataset per column at the root, gzip-compressed
// (level 4) and chunked by `block` rows, each with its `units` attribute; the columns of
// results.h record_table's steps: step, time_s, ground_acceleration_m_per_s2, u, v and a of each
// recorded DOF (RunHeader.recorded_dofs; names by results/column_names.h), command, measured and
// force of each actuator, lateness_s, overrun. The root has `columns` (the names, comma-separated)
// and `complete` (0, then 1 once the footer came and every row is written).
// Rows are held until `block` are in, then appended to every dataset and the file flushed to the
// OS: a process killed mid-run leaves a file that reads with every block written before (at most
// block - 1 steps short of the record, which keeps them). The links' lags are in the record only.
// The first failure (the file cannot be created or written) is kept (failure()) and nothing is
// written after it; the run itself goes on, and its record holds everything.

#include <cstddef>
#include <filesystem>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "runtime/record/record.h"

namespace rths::results {

class RecordH5Writer final : public runtime::RecordObserver {
 public:
  explicit RecordH5Writer(std::filesystem::path path, std::size_t block = 1024);
  ~RecordH5Writer() override;  // writes the rows still held
  RecordH5Writer(const RecordH5Writer&) = delete;
  RecordH5Writer& operator=(const RecordH5Writer&) = delete;

  void on_entry(std::string_view frame) override;
  // Writes the rows still held and closes the file (complete = 1 when the footer came). Once.
  void close();
  std::size_t rows_written() const { return rows_written_; }
  const std::string& failure() const { return failure_; }
  const std::filesystem::path& path() const { return path_; }

 private:
  struct File;
  void open(const runtime::RunHeader& header);
  void append(const runtime::StepRecord& step);
  void write_block();
  void fail(const std::string& what);

  std::filesystem::path path_;
  std::size_t block_;
  std::unique_ptr<File> file_;
  std::vector<std::vector<double>> held_;  // per column, the rows not yet written
  std::size_t held_rows_ = 0, rows_written_ = 0;
  int dofs_ = 0, actuators_ = 0;
  bool footer_ = false, closed_ = false;
  std::string failure_;
};

}  // namespace rths::results
