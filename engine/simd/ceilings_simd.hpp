#pragma once
// The fp32 loop of measure_ceilings() (kodawari/backends/simd.hpp) per Highway target.

#include <cstdint>

namespace kodawari::simd {

/// kFmaChains independent fused multiply-add chains of one vector each (a = a m + c, from
/// start, start + 0.01, ...), `iterations` rounds; returns their sum (so that the loop is
/// kept).
inline constexpr std::uint32_t kFmaChains = 12;
using FmaChainsFn = float (*)(std::uint64_t iterations, float multiplier, float addend, float start);
using LanesFn = std::uint32_t (*)();

struct CeilingKernels {
    FmaChainsFn fma_chains = nullptr;
    LanesFn lanes = nullptr;  ///< floats per vector
};

/// The kernels of a Highway target (isa.hpp).
[[nodiscard]] CeilingKernels ceiling_kernels(std::int64_t target);

}  // namespace kodawari::simd
