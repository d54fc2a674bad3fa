// parallel_for (engine/core/parallel.cpp) over its pool of threads: the same ranges as
// threads started per call, every range once, exceptions carried to the caller, and the
// calls the pool cannot serve (nested, concurrent, after fork()) still run in parallel.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <mutex>
#include <optional>
#include <set>
#include <stdexcept>
#include <thread>
#include <utility>
#include <vector>

#include <csignal>
#include <sys/wait.h>
#include <unistd.h>

#include "core/parallel.hpp"

namespace kodawari {
namespace {

using Ranges = std::set<std::pair<std::size_t, std::size_t>>;

Ranges ranges_of(std::size_t n, unsigned threads) {
    Ranges got;
    std::mutex m;
    parallel_for(n, threads, [&](std::size_t begin, std::size_t end) {
        const std::lock_guard lock(m);
        got.insert({begin, end});
    });
    return got;
}

// What the ranges must be: n p / parts .. n (p + 1) / parts, as before the pool.
Ranges expected(std::size_t n, unsigned threads) {
    const std::size_t parts = std::min<std::size_t>(std::max(1u, threads), std::max<std::size_t>(n, 1));
    Ranges r;
    for (std::size_t p = 0; p < parts; ++p) r.insert({n * p / parts, n * (p + 1) / parts});
    return r;
}

// True when a call's `parts` ranges all ran at once, each seeing the others start within
// 5 s: the pool's workers exist and took the ranges the caller could not (the caller waits
// in range 0, so the ranges after it are run by workers or not at all in time).
bool ranges_run_at_once(unsigned parts) {
    std::atomic<unsigned> started{0};
    std::atomic<bool> all{true};
    parallel_for(parts, parts, [&](std::size_t, std::size_t) {
        started.fetch_add(1);
        const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(5);
        while (started.load() < parts) {
            if (std::chrono::steady_clock::now() >= until) {
                all.store(false);
                return;
            }
            std::this_thread::yield();
        }
    });
    return all.load();
}

// A forked child's wait status, or none (the child killed) when it has not exited within
// 30 s, a thousand times what the children here take.
std::optional<int> exit_status(pid_t child) {
    int status = 0;
    for (int waited = 0; waited < 3000; ++waited) {
        if (waitpid(child, &status, WNOHANG) == child) return status;
        std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    kill(child, SIGKILL);
    waitpid(child, &status, 0);
    return std::nullopt;
}

TEST(Parallel, RangesAreFixedByTheCountAndThreadsAlone) {
    // Counts below, at and above the thread counts, over and over (the pool's workers
    // are reused and grow with the largest count asked for).
    for (int round = 0; round < 50; ++round) {
        for (const std::size_t n : {0u, 1u, 2u, 3u, 7u, 1000u, 1001u}) {
            for (const unsigned threads : {1u, 2u, 3u, 5u, 16u}) {
                ASSERT_EQ(ranges_of(n, threads), expected(n, threads)) << "n " << n << ", threads " << threads;
            }
        }
    }
}

TEST(Parallel, EveryIndexOnceAndTheRangesOnSeveralThreads) {
    const std::size_t n = 100'003;
    std::vector<std::atomic<int>> hits(n);
    std::mutex m;
    std::set<std::thread::id> ids;
    for (int round = 0; round < 20; ++round) {
        parallel_for(n, 4, [&](std::size_t begin, std::size_t end) {
            for (std::size_t i = begin; i < end; ++i) hits[i].fetch_add(1);
            // Long enough that the workers wake and take a range of their own.
            std::this_thread::sleep_for(std::chrono::milliseconds(2));
            const std::lock_guard lock(m);
            ids.insert(std::this_thread::get_id());
        });
    }
    for (std::size_t i = 0; i < n; ++i) ASSERT_EQ(hits[i].load(), 20) << "index " << i;
    std::printf("20 calls of 4 ranges ran on %zu threads\n", ids.size());
    EXPECT_GE(ids.size(), 2u) << "the ranges all ran on one thread";
}

TEST(Parallel, AnExceptionReachesTheCallerAfterEveryRangeEnded) {
    std::atomic<int> ended{0};
    EXPECT_THROW(parallel_for(8, 4,
                              [&](std::size_t begin, std::size_t) {
                                  std::this_thread::sleep_for(std::chrono::milliseconds(1));
                                  ended.fetch_add(1);
                                  if (begin == 4) throw std::runtime_error("range 2");
                              }),
                 std::runtime_error);
    EXPECT_EQ(ended.load(), 4);
    // The pool serves the next call.
    EXPECT_EQ(ranges_of(10, 4), expected(10, 4));
}

TEST(Parallel, NestedCallsRunTheirRanges) {
    std::atomic<int> inner{0};
    parallel_for(4, 4, [&](std::size_t, std::size_t) {
        parallel_for(100, 3, [&](std::size_t begin, std::size_t end) { inner.fetch_add(static_cast<int>(end - begin)); });
    });
    EXPECT_EQ(inner.load(), 400);
}

TEST(Parallel, CallsFromSeveralApplicationThreadsAtOnce) {
    // Two simulations on two threads: one call holds the pool, the other starts threads.
    std::vector<std::jthread> apps;
    std::atomic<long> total{0};
    for (int a = 0; a < 4; ++a) {
        apps.emplace_back([&] {
            for (int round = 0; round < 200; ++round) {
                parallel_for(1000, 2, [&](std::size_t begin, std::size_t end) { total.fetch_add(static_cast<long>(end - begin)); });
            }
        });
    }
    apps.clear();  // joins
    EXPECT_EQ(total.load(), 4L * 200 * 1000);
}

TEST(Parallel, AChildAfterForkRunsWithPoolOfItsOwn) {
    // The parent's workers exist and have each run a range: none is still starting at the
    // fork. That matters to the asan lane: its runtime (clang 14's ASan) does not hold its
    // allocator's locks across fork(), and a worker still starting (ASan's thread set-up
    // and the worker's name allocate) at the fork left a lock held forever in the child,
    // whose own workers then hung in ASan's GetFromAllocator (5 runs in 100 on a loaded
    // machine, once in CI). glibc's malloc takes its locks across fork(), so release
    // builds did not have this.
    ASSERT_TRUE(ranges_run_at_once(3)) << "the pool's two workers did not both take a range within 5 s";
    const pid_t child = fork();
    ASSERT_GE(child, 0);
    if (child == 0) {
        // The child's ranges run at once only on workers of its own (the parent's are not
        // there: the caller alone would wait 5 s in each range). exit(), not _exit(): the
        // child's exit joins its pool's workers.
        const bool at_once = ranges_run_at_once(3);
        std::atomic<int> sum{0};
        parallel_for(10, 3, [&](std::size_t begin, std::size_t end) { sum.fetch_add(static_cast<int>(end - begin)); });
        std::exit(at_once && sum.load() == 10 ? 0 : 1);
    }
    // A child that used the parent's pool exits 1 or hangs (on the parent's workers' locks
    // or joining workers it does not have).
    const std::optional<int> status = exit_status(child);
    ASSERT_TRUE(status.has_value()) << "the child did not exit within 30 s";
    EXPECT_TRUE(WIFEXITED(*status) && WEXITSTATUS(*status) == 0) << "status " << *status;
}

// exit() from a range on a pool worker: the exit stops the pool's other workers and leaves
// the calling one (it cannot join itself), and the process ends with the status given.
TEST(Parallel, ExitFromInsideARangeEndsTheProcessWithItsStatus) {
    const pid_t child = fork();
    ASSERT_GE(child, 0);
    if (child == 0) {
        parallel_for(4, 4, [](std::size_t begin, std::size_t) {
            if (begin == 3) std::exit(3);
            std::this_thread::sleep_for(std::chrono::milliseconds(20));
        });
        std::exit(0);
    }
    const std::optional<int> status = exit_status(child);
    ASSERT_TRUE(status.has_value()) << "the child did not exit within 30 s";
    EXPECT_TRUE(WIFEXITED(*status) && WEXITSTATUS(*status) == 3) << "status " << *status;
}

}  // namespace
}  // namespace kodawari
