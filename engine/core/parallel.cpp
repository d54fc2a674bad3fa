#include "core/parallel.hpp"

#include <algorithm>
#include <thread>
#include <vector>

namespace kodawari {

unsigned resolve_threads(unsigned requested) {
    if (requested > 0) return requested;
    return std::max(1u, std::thread::hardware_concurrency());
}

void parallel_for(std::size_t n, unsigned threads, const std::function<void(std::size_t, std::size_t)>& fn) {
    const std::size_t parts = std::min<std::size_t>(std::max(1u, threads), std::max<std::size_t>(n, 1));
    if (parts <= 1) {
        fn(0, n);
        return;
    }
    std::vector<std::jthread> workers;
    workers.reserve(parts - 1);
    for (std::size_t p = 1; p < parts; ++p) {
        workers.emplace_back([&fn, n, parts, p] { fn(n * p / parts, n * (p + 1) / parts); });
    }
    fn(0, n / parts);
}

}  // namespace kodawari
