// What the plots cost against the run, as a user sees it: `rths run CONFIG --no-plots` and
// `rths run CONFIG` (results table, summaries, the benchmark's criteria, and with plots the three
// figures) timed end to end as processes, alternately, `runs` times each (default 5; argv[1]),
// for the RTHS benchmark's case 1 and the paper frame. Prints the median wall-clock time of each
// (s), their ratio with plots / without against issue 39's target of at most 2x, and the machine's
// 1-minute load average before and after (timings on a loaded machine read high and vary). A
// benchmark: prints figures, never part of the suite.
#include <fcntl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

namespace {

double load_average() {
  std::ifstream in("/proc/loadavg");
  double one_minute = -1.0;
  in >> one_minute;
  return one_minute;
}

// Wall-clock seconds of one `rths run`, its output discarded; exits the bench when it fails.
double time_run(const std::string& config, const std::filesystem::path& out, bool plots) {
  std::vector<std::string> words = {RTHS_CLI, "run", config, "--out", out.string()};
  if (!plots) words.push_back("--no-plots");
  std::vector<char*> argv;
  for (std::string& w : words) argv.push_back(w.data());
  argv.push_back(nullptr);
  std::fflush(stdout);  // a child must not inherit (and write again) what is buffered here
  const auto start = std::chrono::steady_clock::now();
  const pid_t pid = fork();
  if (pid == 0) {
    const int null = open("/dev/null", O_WRONLY);
    if (null < 0 || dup2(null, 1) < 0) _exit(127);
    execv(argv[0], argv.data());
    _exit(127);
  }
  int status = 0;
  waitpid(pid, &status, 0);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
    std::fprintf(stderr, "rths run %s failed\n", config.c_str());
    std::exit(1);
  }
  return seconds;
}

double median(std::vector<double> values) {
  std::sort(values.begin(), values.end());
  const std::size_t n = values.size();
  return n % 2 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
}

void measure(const std::string& relative_config, int runs) {
  const std::string config = std::string(RTHS_SOURCE_DIR) + "/" + relative_config;
  const std::filesystem::path out =
      std::filesystem::temp_directory_path() / ("rths_plots_bench_" + std::to_string(getpid()));
  const double load_before = load_average();
  std::vector<double> without, with;
  for (int i = 0; i < runs; ++i) {
    without.push_back(time_run(config, out, false));
    with.push_back(time_run(config, out, true));
  }
  std::filesystem::remove_all(out);
  const double ratio = median(with) / median(without);
  std::printf(
      "%-36s --no-plots %6.2f s, with plots %6.2f s (medians of %d): %.2fx (target <= 2x: %s); "
      "load %.2f -> %.2f\n",
      relative_config.c_str(), median(without), median(with), runs, ratio,
      ratio <= 2.0 ? "met" : "MISSED", load_before, load_average());
}

}  // namespace

int main(int argc, char** argv) {
  const int runs = argc > 1 ? std::max(1, std::atoi(argv[1])) : 5;
  measure("configs/benchmark/case_1.textproto", runs);
  measure("configs/paper_frame.textproto", runs);
  return 0;
}
