#include "slurm/sbatch.h"

#include <regex>
#include <stdexcept>

#include "util/atomic_file.h"

namespace rths::slurm {
namespace {

// Single-quoted for bash: safe for any path.
std::string quoted(const std::string& text) {
  std::string out = "'";
  for (char c : text) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

std::string shard_file(const SweepJob& job, std::size_t index) {
  return (job.out / "shards" /
          ("sweep.shard-" + std::to_string(index) + "-of-" + std::to_string(job.shards) + ".csv"))
      .string();
}

std::string common_header(const SweepJob& job, const std::string& name, const std::string& log) {
  std::string h = "#!/bin/bash\n#SBATCH --job-name=" + name +
                  "\n#SBATCH --output=" + (job.out / "logs" / log).string() + "\n";
  if (!job.partition.empty()) h += "#SBATCH --partition=" + job.partition + "\n";
  h += "#SBATCH --time=" + job.time + "\n#SBATCH --mem=" + job.memory + "\n";
  return h;
}

}  // namespace

void validate(const SweepJob& job) {
  if (job.shards == 0) throw std::invalid_argument("--shards must be at least 1");
  if (job.threads < 1)
    throw std::invalid_argument("--threads must be at least 1 for a Slurm job (its cpus-per-task)");
  static const std::regex time(
      R"(^(\d+|\d+:\d{2}|\d+:\d{2}:\d{2}|\d+-\d+|\d+-\d+:\d{2}|\d+-\d+:\d{2}:\d{2})$)");
  if (!std::regex_match(job.time, time)) {
    throw std::invalid_argument(
        "--time '" + job.time +
        "' is not a Slurm time (minutes, MM:SS, HH:MM:SS, D-HH, D-HH:MM:SS)");
  }
  static const std::regex memory(R"(^\d+[KMGT]?$)");
  if (!std::regex_match(job.memory, memory)) {
    throw std::invalid_argument("--mem '" + job.memory +
                                "' is not a Slurm memory size (e.g. 500M, 2G)");
  }
  static const std::regex partition(R"(^[A-Za-z0-9_.,-]*$)");
  if (!std::regex_match(job.partition, partition)) {
    throw std::invalid_argument("--partition '" + job.partition +
                                "' has characters a partition name cannot have");
  }
}

SweepScripts sweep_scripts(const SweepJob& job) {
  validate(job);
  const std::string rths = quoted(job.rths.string()), config = quoted(job.config.string());
  const std::string n = std::to_string(job.shards), threads = std::to_string(job.threads);
  SweepScripts s;
  s.array = common_header(job, "rths-sweep", "shard-%a.out") + "#SBATCH --array=0-" +
            std::to_string(job.shards - 1) + "\n#SBATCH --cpus-per-task=" + threads +
            "\n# One task per shard of the sweep grid; `rths sweep merge` (sweep_merge.sbatch) "
            "joins them.\n"
            "set -euo pipefail\n"
            "exec " +
            rths + " sweep " + config + " --shard \"$SLURM_ARRAY_TASK_ID/" + n + "\" --out " +
            quoted((job.out / "shards").string()) + " --threads " + threads + " --no-plots\n";
  s.merge = common_header(job, "rths-sweep-merge", "merge.out") +
            "# Runs after every array task succeeded (submit.sh: --dependency=afterok).\n"
            "set -euo pipefail\n"
            "exec " +
            rths + " sweep merge " + quoted((job.out / "sweep.csv").string());
  for (std::size_t i = 0; i < job.shards; ++i) s.merge += " \\\n  " + quoted(shard_file(job, i));
  s.merge += "\n";
  s.submit =
      "#!/bin/bash\n"
      "# Submits the sweep's array job and its merge job; prints both job ids (array first).\n"
      "set -euo pipefail\n"
      "array=$(sbatch --parsable " +
      quoted((job.out / "sweep_array.sbatch").string()) +
      ")\n"
      "array=${array%%;*}\n"
      "echo \"$array\"\n"
      "merge=$(sbatch --parsable --dependency=afterok:\"$array\" --kill-on-invalid-dep=yes " +
      quoted((job.out / "sweep_merge.sbatch").string()) +
      ")\n"
      "echo \"${merge%%;*}\"\n";
  return s;
}

std::vector<std::filesystem::path> write_sweep_job(const SweepJob& job) {
  const SweepScripts scripts = sweep_scripts(job);
  std::error_code ec;
  for (const char* sub : {"logs", "shards"}) {
    std::filesystem::create_directories(job.out / sub, ec);
    if (ec)
      throw std::runtime_error("cannot create " + (job.out / sub).string() + ": " + ec.message());
  }
  std::vector<std::filesystem::path> written;
  for (const auto& [name, text] :
       {std::pair{"sweep_array.sbatch", &scripts.array},
        std::pair{"sweep_merge.sbatch", &scripts.merge}, std::pair{"submit.sh", &scripts.submit}}) {
    util::AtomicFile file(job.out / name);
    file.stream() << *text;
    file.commit();
    std::filesystem::permissions(
        job.out / name, std::filesystem::perms::owner_exec | std::filesystem::perms::group_exec,
        std::filesystem::perm_options::add, ec);
    written.push_back(job.out / name);
  }
  return written;
}

}  // namespace rths::slurm
