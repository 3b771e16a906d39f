#include "cli/console.h"

#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <iostream>

namespace rths::cli {

namespace {
double monotonic_seconds() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}
}  // namespace

ProgressReporter::ProgressReporter(std::string label, std::string unit, bool enabled)
    : label_(std::move(label)),
      unit_(std::move(unit)),
      enabled_(enabled),
      tty_(isatty(STDERR_FILENO) != 0),
      start_seconds_(monotonic_seconds()) {}

void ProgressReporter::update(std::size_t done, std::size_t total) {
  if (!enabled_ || total == 0) return;
  const double seconds = monotonic_seconds() - start_seconds_;
  const double fraction = static_cast<double>(std::min(done, total)) / static_cast<double>(total);
  if (tty_) {
    if (done < total && seconds - last_draw_ < 0.1) return;
    last_draw_ = seconds;
    constexpr int kWidth = 30;
    const int filled = static_cast<int>(fraction * kWidth);
    std::fprintf(stderr, "\r%s [%s%s] %3.0f%% %zu/%zu %s %.1f s", label_.c_str(),
                 std::string(filled, '#').c_str(), std::string(kWidth - filled, '.').c_str(),
                 100 * fraction, done, total, unit_.c_str(), seconds);
    if (done >= total) std::fputc('\n', stderr);
  } else {
    const int decile = static_cast<int>(std::floor(fraction * 10));
    if (decile <= last_decile_) return;
    last_decile_ = decile;
    std::fprintf(stderr, "%s: %3d%% (%zu/%zu %s, %.1f s)\n", label_.c_str(), decile * 10, done,
                 total, unit_.c_str(), seconds);
  }
  std::fflush(stderr);
}

void print_warning(const std::string& message) {
  std::cerr << "rths: warning: " << message << "\n";
}

}  // namespace rths::cli
