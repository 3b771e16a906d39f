#include "study/memory_budget.h"

#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace rths::study {

namespace {

std::uint64_t rlimit_bytes(int resource) {
  rlimit limit{};
  if (getrlimit(resource, &limit) != 0 || limit.rlim_cur == RLIM_INFINITY)
    return std::numeric_limits<std::uint64_t>::max();
  return static_cast<std::uint64_t>(limit.rlim_cur);
}

}  // namespace

std::uint64_t memory_limit_bytes() {
  if (const char* given = std::getenv("RTHS_MEMORY_LIMIT"); given && *given) {
    const long long value = std::atoll(given);
    if (value > 0) return static_cast<std::uint64_t>(value);
  }
  const long pages = sysconf(_SC_PHYS_PAGES), page = sysconf(_SC_PAGESIZE);
  std::uint64_t limit = pages > 0 && page > 0 ? static_cast<std::uint64_t>(pages) *
                                                    static_cast<std::uint64_t>(page) / 2
                                              : std::numeric_limits<std::uint64_t>::max();
  limit = std::min({limit, rlimit_bytes(RLIMIT_AS), rlimit_bytes(RLIMIT_DATA)});
  return limit;
}

void require_memory(std::uint64_t rows, std::uint64_t bytes_per_row, const std::string& what) {
  const std::uint64_t limit = memory_limit_bytes();
  const bool overflow =
      bytes_per_row != 0 && rows > std::numeric_limits<std::uint64_t>::max() / bytes_per_row;
  if (!overflow && rows * bytes_per_row <= limit) return;
  const double mib = 1024.0 * 1024.0;
  std::ostringstream why;
  why << what << " keeps " << rows << " rows x " << bytes_per_row << " bytes = "
      << (overflow ? std::numeric_limits<double>::infinity()
                   : static_cast<double>(rows * bytes_per_row) / mib)
      << " MiB, more than the memory limit of " << static_cast<double>(limit) / mib
      << " MiB (half this machine's memory, or RTHS_MEMORY_LIMIT); use a longer dt or a "
         "shorter motion";
  throw std::invalid_argument(why.str());
}

}  // namespace rths::study
