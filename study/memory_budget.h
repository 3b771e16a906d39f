#pragma once
// The memory a run keeps, checked before it is allocated: a step as short as the documented
// range allows (1e-6 s) over a long record keeps tens of millions of rows, which ended in
// std::bad_alloc (exit 3) halfway through allocating. A run that cannot fit is refused instead,
// naming its estimate and the limit.
//
// memory_limit_bytes(): RTHS_MEMORY_LIMIT (bytes) when set and positive; else half of this
// machine's physical memory, and no more than RLIMIT_AS / RLIMIT_DATA when those are set.
// require_memory(rows, bytes_per_row, what): throws std::invalid_argument
//   "WHAT keeps R rows x B bytes = X MiB, more than the memory limit of L MiB (...)" when
//   rows x bytes_per_row exceeds the limit (overflow counts as exceeding). Loading only.

#include <cstdint>
#include <string>

namespace rths::study {

std::uint64_t memory_limit_bytes();

void require_memory(std::uint64_t rows, std::uint64_t bytes_per_row, const std::string& what);

}  // namespace rths::study
