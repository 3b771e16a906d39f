#pragma once
// Runs a command line in a shell and keeps its exit code and its output (stdout and stderr
// together): how the CLI tests drive the `rths` program as a user would.

#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <string>

namespace rths::test {

struct CommandOutcome {
  int exit_code = -1;  // -1: could not start, or ended by a signal
  std::string output;  // stdout and stderr
};

inline CommandOutcome run_command_line(const std::string& command_line) {
  CommandOutcome outcome;
  FILE* pipe = popen((command_line + " 2>&1").c_str(), "r");
  if (!pipe) return outcome;
  std::array<char, 4096> buffer{};
  std::size_t n;
  while ((n = std::fread(buffer.data(), 1, buffer.size(), pipe)) > 0)
    outcome.output.append(buffer.data(), n);
  const int status = pclose(pipe);
  outcome.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return outcome;
}

}  // namespace rths::test
