#pragma once
// A sweep as a Slurm job: an sbatch array with one task per shard, each running
//   rths sweep CONFIG --shard $SLURM_ARRAY_TASK_ID/N --out OUT/shards --threads C --no-plots
// and a merge job that runs after every task succeeded (--dependency=afterok:<array>):
//   rths sweep merge OUT/sweep.csv OUT/shards/sweep.shard-{0..N-1}-of-N.csv
// Files written into OUT: sweep_array.sbatch, sweep_merge.sbatch, and submit.sh, which submits
// both and prints the two job ids (array first). Logs go to OUT/logs/. Every path in the scripts
// is absolute, so they run from any working directory on the cluster's shared file system.

#include <filesystem>
#include <string>
#include <vector>

namespace rths::slurm {

struct SweepJob {
  std::filesystem::path rths;     // the rths executable the nodes run
  std::filesystem::path config;   // study config with a `sweep` block
  std::filesystem::path out;      // job folder
  std::size_t shards = 4;         // array tasks
  std::string partition;          // empty: the cluster's default
  std::string time = "01:00:00";  // per task: minutes, MM:SS, HH:MM:SS, D-HH or D-HH:MM:SS
  std::string memory = "1G";      // per task: a number with an optional K, M, G or T suffix
  int threads = 1;                // cpus-per-task, and the sweep's --threads
};

// Throws std::invalid_argument naming the option when a value would not be accepted by sbatch
// (or could break the script): shards 0, threads < 1, a malformed time or memory, a partition
// name with characters other than letters, digits, '_', '-', '.', ','.
void validate(const SweepJob& job);

struct SweepScripts {
  std::string array, merge, submit;  // file contents
};
// The scripts' text (validates first).
SweepScripts sweep_scripts(const SweepJob& job);

// Writes the scripts into job.out (creating it, logs/ and shards/) and returns their paths:
// array, merge, submit. Throws std::runtime_error naming a file it cannot write.
std::vector<std::filesystem::path> write_sweep_job(const SweepJob& job);

}  // namespace rths::slurm
