// The machine's ceilings (kodawari/backends/simd.hpp, measure_ceilings()): the fp32 rate of
// independent fused multiply-adds on every thread, and the STREAM triad's memory rate. What
// docs/performance.md sets each kernel's rate against, measured by the same binary on the
// same machine rather than taken from notes kept elsewhere. Compiled once per instruction
// set by Highway's foreach_target.h, so the fp32 loop runs on the ISA a cpu backend uses.
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "simd/ceilings_simd.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep
#include <hwy/highway.h>

#include <cstdint>

#include "simd/ceilings_simd.hpp"

HWY_BEFORE_NAMESPACE();
namespace kodawari::simd {
namespace HWY_NAMESPACE {
namespace {

namespace hn = hwy::HWY_NAMESPACE;
using D = hn::ScalableTag<float>;

// `iterations` rounds of kFmaChains independent a = a * m + c per vector: enough chains in
// flight to cover a fused multiply-add's latency on every pipe (4 cycles x 2 pipes on
// Zen 4 and recent Intel cores: 8; 12 leave room). Each chain depends on itself only, so
// neither the hardware nor the compiler can shorten it; the sum keeps it from being
// dropped. Without FMA instructions (sse4, scalar) MulAdd is a multiply and an add: the
// same 2 flops a lane.
float fma_chains(std::uint64_t iterations, float multiplier, float addend, float start) {
    static_assert(kFmaChains == 12, "the loop below writes out 12 chains");
    const D d;
    // The operands come from the caller at run time: with constants GCC 12 folded the
    // whole loop of the non-FMA targets into its result.
    const auto m = hn::Set(d, multiplier);
    const auto c = hn::Set(d, addend);
    const auto step = hn::Set(d, 0.01f);
    auto a0 = hn::Set(d, start), a1 = hn::Add(a0, step), a2 = hn::Add(a1, step), a3 = hn::Add(a2, step);
    auto a4 = hn::Add(a3, step), a5 = hn::Add(a4, step), a6 = hn::Add(a5, step), a7 = hn::Add(a6, step);
    auto a8 = hn::Add(a7, step), a9 = hn::Add(a8, step), a10 = hn::Add(a9, step), a11 = hn::Add(a10, step);
    for (std::uint64_t i = 0; i < iterations; ++i) {
        a0 = hn::MulAdd(a0, m, c);
        a1 = hn::MulAdd(a1, m, c);
        a2 = hn::MulAdd(a2, m, c);
        a3 = hn::MulAdd(a3, m, c);
        a4 = hn::MulAdd(a4, m, c);
        a5 = hn::MulAdd(a5, m, c);
        a6 = hn::MulAdd(a6, m, c);
        a7 = hn::MulAdd(a7, m, c);
        a8 = hn::MulAdd(a8, m, c);
        a9 = hn::MulAdd(a9, m, c);
        a10 = hn::MulAdd(a10, m, c);
        a11 = hn::MulAdd(a11, m, c);
    }
    const auto sum = hn::Add(hn::Add(hn::Add(hn::Add(a0, a1), hn::Add(a2, a3)), hn::Add(hn::Add(a4, a5), hn::Add(a6, a7))),
                             hn::Add(hn::Add(a8, a9), hn::Add(a10, a11)));
    return hn::GetLane(hn::SumOfLanes(d, sum));
}

std::uint32_t lanes() { return static_cast<std::uint32_t>(hn::Lanes(D())); }

}  // namespace

CeilingKernels ceiling_kernels() { return {&fma_chains, &lanes}; }

}  // namespace HWY_NAMESPACE
}  // namespace kodawari::simd
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
#include "simd/dispatch.hpp"

namespace kodawari::simd {

CeilingKernels ceiling_kernels(std::int64_t target) { KW_SIMD_SELECT(target, ceiling_kernels) }

}  // namespace kodawari::simd
#endif
