#pragma once
// Splits [0, n) into one contiguous range per thread. Ranges are fixed by n and the
// thread count alone, so results never depend on scheduling.

#include <cstddef>
#include <functional>

#include "core/internal_api.hpp"

namespace kodawari {

/// Threads to use for `requested` (0 = hardware concurrency, at least 1).
[[nodiscard]] KODAWARI_INTERNAL unsigned resolve_threads(unsigned requested);

/// Calls fn(begin, end) for `threads` ranges covering [0, n), in parallel, and waits (on a
/// pool of threads kept for the process, parallel.cpp). An exception thrown by fn reaches
/// the caller (the first one, after every range ended).
KODAWARI_INTERNAL void parallel_for(std::size_t n, unsigned threads, const std::function<void(std::size_t,
                                    std::size_t)>& fn);

}  // namespace kodawari
