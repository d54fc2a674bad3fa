#pragma once
// The Highway target a cpu backend's kernels run on (kodawari/backends/simd.hpp is the public side).
// Each backend chooses one at construction and keeps that target's kernel functions
// (rods_simd.hpp, birds_simd.hpp, poses_simd.hpp): nothing process-wide, so two backends
// on different instruction sets work side by side (the tests run two).

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "core/internal_api.hpp"
#include "kodawari/core/result.hpp"

namespace kodawari::simd {

/// An instruction set: Highway's target bit (HWY_AVX3, ...), the public name, floats per vector.
struct Isa {
    std::int64_t target = 0;
    std::string name;
    unsigned lanes = 0;
};

/// The instruction set for BackendOptions::isa == `requested` (kodawari::simd_isa()).
[[nodiscard]] KODAWARI_INTERNAL Result<Isa> choose_isa(std::string_view requested);

/// The instruction sets this machine runs up to `widest`, widest first, one per vector
/// width: the narrower ones a backend may take for a batch with few lanes in use, where
/// a narrower vector costs less (rods_simd.hpp). Every one gives the same bits.
[[nodiscard]] KODAWARI_INTERNAL std::vector<Isa> isas_up_to(const Isa& widest);

/// Chains, birds or instances per batch: a batch is one AVX-512 vector of floats, two AVX2
/// vectors, four SSE4 ones, so that the backends' structure-of-arrays layout is the same
/// on every instruction set and a batch's rows are whole 64-byte cache lines.
inline constexpr std::size_t kBatchLanes = 16;

}  // namespace kodawari::simd
