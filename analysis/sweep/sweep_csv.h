#pragma once
// Sweep CSVs: a header (SI, the unit in every column name; errors in percent, E_peak and E_rms
// first, the paper's NRMSE and Eq. 2 after) and the rows; what the
// rows are (grid hash, points, shard i/N) goes in a sidecar JSON, sweep_sidecar_path(csv), so the
// CSV itself is plain for any CSV reader. Numbers are written with 17 significant digits so
// merged shards equal an unsharded run byte for byte. Both files are written to a temporary file
// and renamed (util/atomic_file.h), so no half-written CSV looks complete.

#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

#include "analysis/sweep/sweep_grid.h"
#include "analysis/sweep/sweep_run.h"

namespace rths::analysis {

// "sweep.csv" -> "sweep.meta.json".
std::filesystem::path sweep_sidecar_path(const std::filesystem::path& csv);
void write_sweep_csv(const std::filesystem::path& path, const SweepGrid& grid, const Shard& shard,
                     const std::vector<SweepRow>& rows);

struct SweepCsv {
  std::string grid_hash;
  std::size_t points = 0;
  Shard shard;
  std::string header;
  std::vector<std::size_t> indices;  // one per row, as in the file
  std::vector<std::string> lines;    // the rows' text
};
// Throws std::invalid_argument naming the file and line when it is not a sweep CSV.
SweepCsv read_sweep_csv(const std::filesystem::path& path);

// Joins shard CSVs into one complete CSV at `out`. Throws std::invalid_argument naming the
// files when they come from different grids, overlap (a duplicated index or shard), or leave
// indices missing. Returns the merged table.
SweepCsv merge_sweep_csvs(const std::vector<std::filesystem::path>& shards,
                          const std::filesystem::path& out);

// Rows parsed back from a sweep CSV (names of motion and model kept as text). Throws
// std::invalid_argument naming `source` and the row and column that is not a number.
std::vector<SweepTableRow> parse_sweep_rows(const SweepCsv& csv, const std::string& source);

}  // namespace rths::analysis
