// slurm::sweep_scripts / write_sweep_job: the array, merge and submit scripts, and bad options.
#include "slurm/sbatch.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <fstream>
#include <sstream>

namespace rths::slurm {
namespace {

SweepJob job() {
  SweepJob j;
  j.rths = "/opt/rths/bin/rths";
  j.config = "/home/lab/it's here/sweep.textproto";
  j.out = "/scratch/job";
  j.shards = 3;
  j.partition = "short";
  j.time = "00:30:00";
  j.memory = "2G";
  j.threads = 2;
  return j;
}

TEST(SbatchTest, ArrayHasOneTaskPerShardAndRunsItsShard) {
  const SweepScripts s = sweep_scripts(job());
  EXPECT_EQ(s.array.rfind("#!/bin/bash\n", 0), 0u);
  for (const char* line :
       {"#SBATCH --array=0-2\n", "#SBATCH --partition=short\n", "#SBATCH --time=00:30:00\n",
        "#SBATCH --mem=2G\n", "#SBATCH --cpus-per-task=2\n",
        "#SBATCH --output=/scratch/job/logs/shard-%a.out\n"}) {
    EXPECT_NE(s.array.find(line), std::string::npos) << line << "\n" << s.array;
  }
  EXPECT_NE(
      s.array.find(
          "exec '/opt/rths/bin/rths' sweep '/home/lab/it'\\''s here/sweep.textproto' "
          "--shard \"$SLURM_ARRAY_TASK_ID/3\" --out '/scratch/job/shards' --threads 2 --no-plots"),
      std::string::npos)
      << s.array;
}

TEST(SbatchTest, MergeJoinsEveryShardAfterTheArraySucceeded) {
  const SweepScripts s = sweep_scripts(job());
  EXPECT_NE(s.merge.find("sweep merge '/scratch/job/sweep.csv'"), std::string::npos) << s.merge;
  for (int i = 0; i < 3; ++i) {
    const std::string shard =
        "'/scratch/job/shards/sweep.shard-" + std::to_string(i) + "-of-3.csv'";
    EXPECT_NE(s.merge.find(shard), std::string::npos) << shard;
  }
  EXPECT_EQ(s.merge.find("--array"), std::string::npos);
  EXPECT_NE(s.submit.find("--dependency=afterok:\"$array\""), std::string::npos) << s.submit;
  EXPECT_NE(s.submit.find("sbatch --parsable '/scratch/job/sweep_array.sbatch'"), std::string::npos)
      << s.submit;
}

TEST(SbatchTest, NoPartitionLineWhenTheDefaultIsWanted) {
  SweepJob j = job();
  j.partition.clear();
  EXPECT_EQ(sweep_scripts(j).array.find("--partition"), std::string::npos);
}

TEST(SbatchTest, RejectsWhatSbatchWouldRejectNamingTheOption) {
  const auto message = [](SweepJob j) {
    try {
      sweep_scripts(j);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  SweepJob j = job();
  j.time = "half an hour";
  EXPECT_NE(message(j).find("--time 'half an hour'"), std::string::npos);
  for (const char* ok : {"30", "30:00", "2:00:00", "1-12", "1-12:00:00"}) {
    j.time = ok;
    EXPECT_EQ(message(j), "accepted") << ok;
  }
  j = job();
  j.memory = "2 GB";
  EXPECT_NE(message(j).find("--mem"), std::string::npos);
  j = job();
  j.partition = "short; rm -rf /";
  EXPECT_NE(message(j).find("--partition"), std::string::npos);
  j = job();
  j.shards = 0;
  EXPECT_NE(message(j).find("--shards"), std::string::npos);
}

TEST(SbatchTest, WritesExecutableScriptsAndTheFoldersTheJobsUse) {
  SweepJob j = job();
  j.out = std::filesystem::temp_directory_path() / ("rths_sbatch_" + std::to_string(getpid()));
  std::filesystem::remove_all(j.out);
  const auto written = write_sweep_job(j);
  ASSERT_EQ(written.size(), 3u);
  EXPECT_EQ(written[2].filename(), "submit.sh");
  EXPECT_TRUE(std::filesystem::is_directory(j.out / "logs"));
  EXPECT_TRUE(std::filesystem::is_directory(j.out / "shards"));
  EXPECT_NE(std::filesystem::status(written[0]).permissions() & std::filesystem::perms::owner_exec,
            std::filesystem::perms::none);
  std::ifstream in(written[0]);
  std::stringstream text;
  text << in.rdbuf();
  EXPECT_EQ(text.str(), sweep_scripts(j).array);
  std::filesystem::remove_all(j.out);
}

}  // namespace
}  // namespace rths::slurm
