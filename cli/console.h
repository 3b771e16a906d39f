#pragma once
// What a command says on stderr besides its result: a long command's progress, and warnings.
#include <cstddef>
#include <string>

namespace rths::cli {

// Progress of a long command on stderr: one bar redrawn at most every 0.1 s when stderr is a
// terminal; otherwise (a log, a batch job) a plain line per 10 %, so logs stay short. `label`
// starts each line ("sweep", "sites"), `unit` names what is counted ("points", "cases").
class ProgressReporter {
 public:
  ProgressReporter(std::string label, std::string unit, bool enabled = true);
  void update(std::size_t done, std::size_t total);

 private:
  std::string label_, unit_;
  bool enabled_, tty_;
  double start_seconds_;
  double last_draw_ = -1;
  int last_decile_ = 0;
};

// "rths: warning: ..." on stderr.
void print_warning(const std::string& message);

}  // namespace rths::cli
