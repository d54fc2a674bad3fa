// measure_ceilings() (kodawari/backends/simd.hpp): the fp32 loop (ceilings_simd.cpp) and
// STREAM's triad (McCalpin, "Memory Bandwidth and Machine Balance in Current High
// Performance Computers", IEEE TCCA Newsletter, 1995: a[i] = b[i] + s c[i], 24 bytes an
// element in doubles, here 12 in floats) on `threads` threads released together.
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <memory>
#include <new>
#include <string>
#include <thread>
#include <vector>

#include "kodawari/backends/simd.hpp"
#include "simd/ceilings_simd.hpp"
#include "simd/isa.hpp"

namespace kodawari {
namespace {

using Clock = std::chrono::steady_clock;

// Runs work(t) on threads 0..n-1, all released at once; the seconds from the release to
// the last one's end. Threads of its own rather than parallel_for's pool: tried, the
// triad through parallel_for measured 26-35 GB/s on one thread and 43-45 on two against
// 36-37 and 47-49 here, interleaved in one session (cause not found); a ceiling is the
// most a machine gives.
template <typename Work>
double timed_on_threads(unsigned n, const Work& work) {
    std::atomic<bool> go{false};
    std::atomic<unsigned> ready{0};
    std::vector<std::thread> pool;
    pool.reserve(n);
    for (unsigned t = 0; t < n; ++t) {
        pool.emplace_back([&, t] {
            ready.fetch_add(1);
            while (!go.load(std::memory_order_acquire)) std::this_thread::yield();
            work(t);
        });
    }
    while (ready.load() < n) std::this_thread::yield();
    const auto start = Clock::now();
    go.store(true, std::memory_order_release);
    for (std::thread& thread : pool) thread.join();
    return std::chrono::duration<double>(Clock::now() - start).count();
}

}  // namespace

Result<MachineCeilings> measure_ceilings(std::string_view isa, unsigned threads, std::size_t triad_bytes) {
    if (threads < 1 || threads > 1024) {
        return make_error(Error::Kind::InvalidInput, "measure_ceilings: threads: expected 1 to 1024, got " + std::to_string(threads));
    }
    constexpr std::size_t kMin = std::size_t{3} << 20, kMax = std::size_t{64} << 30;
    if (triad_bytes < kMin || triad_bytes > kMax) {
        return make_error(Error::Kind::InvalidInput, "measure_ceilings: triad_bytes: expected 3 MiB to 64 GiB, got " +
                                                         std::to_string(triad_bytes) + " bytes");
    }
    auto chosen = simd::choose_isa(isa);
    if (!chosen) return make_error(Error::Kind::InvalidInput, "measure_ceilings: isa: " + chosen.error().message);
    const simd::CeilingKernels kernels = simd::ceiling_kernels(chosen.value().target);

    MachineCeilings out;
    out.isa = chosen.value().name;
    out.threads = threads;

    // The fp32 loop: about 0.15 s at 3 GHz whatever the width (one vector operation a
    // chain a round); a warm-up round first brings the cores to their clock.
    constexpr std::uint64_t kRounds = 40'000'000;
    std::vector<float> sink(threads, 0.0f);
    volatile float multiplier = 0.9999999f, addend = 1e-7f, start = 1.0f;  // unknown to the compiler
    const float m0 = multiplier, c0 = addend, a0 = start;
    timed_on_threads(threads, [&](unsigned t) { sink[t] = kernels.fma_chains(kRounds / 10, m0, c0, a0); });
    const double fma_seconds = timed_on_threads(threads, [&](unsigned t) { sink[t] += kernels.fma_chains(kRounds, m0, c0, a0); });
    const double lanes = kernels.lanes();
    out.fp32_flops = 2.0 * lanes * simd::kFmaChains * static_cast<double>(kRounds) * threads / fma_seconds;
    volatile float keep = 0.0f;  // the chains' sums are used
    for (float s : sink) keep = keep + s;

    // The triad: each thread touches its own range first (so that its pages are where it
    // runs), then three passes; the best counts, as in STREAM.
    const std::size_t n = triad_bytes / (3 * sizeof(float));
    std::unique_ptr<float[]> a(new (std::nothrow) float[n]), b(new (std::nothrow) float[n]), c(new (std::nothrow) float[n]);
    if (!a || !b || !c) {
        return make_error(Error::Kind::Internal, "measure_ceilings: cannot allocate the triad's " + std::to_string(3 * n * sizeof(float)) + " bytes");
    }
    const auto range = [&](unsigned t) { return std::pair{n * t / threads, n * (t + 1) / threads}; };
    timed_on_threads(threads, [&](unsigned t) {
        const auto [begin, end] = range(t);
        for (std::size_t i = begin; i < end; ++i) a[i] = 0.0f, b[i] = 1.0f, c[i] = 2.0f;
    });
    double best = 0.0;
    for (int pass = 0; pass < 3; ++pass) {
        const float s = 3.0f + static_cast<float>(pass);
        const double seconds = timed_on_threads(threads, [&](unsigned t) {
            const auto [begin, end] = range(t);
            float* __restrict pa = a.get();
            const float* __restrict pb = b.get();
            const float* __restrict pc = c.get();
            for (std::size_t i = begin; i < end; ++i) pa[i] = pb[i] + s * pc[i];
        });
        best = std::max(best, static_cast<double>(3 * n * sizeof(float)) / seconds);
    }
    keep = keep + a[n / 2];
    out.triad_bytes_per_second = best;
    out.triad_bytes = 3 * n * sizeof(float);
    return out;
}

}  // namespace kodawari
