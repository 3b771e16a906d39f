#pragma once
// parallel_for: runs body(i) for i = 0..count-1 on `threads` std::threads (the caller's thread is
// one of them). Items are handed out one at a time from an atomic counter, so uneven items
// balance. The first exception thrown by any item stops the hand-out and is rethrown in the
// caller once every thread has joined. threads <= 0 means std::thread::hardware_concurrency().

#include <cstddef>
#include <functional>

namespace rths::util {

int resolve_threads(int threads);
void parallel_for(std::size_t count, int threads, const std::function<void(std::size_t)>& body);

}  // namespace rths::util
