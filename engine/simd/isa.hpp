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

/// What a vector of a kernel costs on each width, relative to a lane of the scalar target,
/// as measured for that kernel (the backends' tables say where).
struct VectorCosts {
    double w16 = 1.0, w8 = 1.0, w4 = 1.0, w1 = 1.0;  ///< avx512, avx2, sse4 (and emu128), scalar
    [[nodiscard]] double of(unsigned lanes) const { return lanes >= 16 ? w16 : lanes >= 8 ? w8 : lanes >= 4 ? w4 : w1; }
};

/// The index into `widths` (isas_up_to's) whose vectors cost least for a batch of `count`
/// lanes in use: ceil(count / lanes) vectors at costs.of(lanes) each; the widest on a tie.
[[nodiscard]] KODAWARI_INTERNAL std::size_t cheapest_width(const std::vector<Isa>& widths, std::uint32_t count,
                                                           const VectorCosts& costs);

/// Chains, birds or instances per batch: a batch is one AVX-512 vector of floats, two AVX2
/// vectors, four SSE4 ones, so that the backends' structure-of-arrays layout is the same
/// on every instruction set and a batch's rows are whole 64-byte cache lines.
inline constexpr std::size_t kBatchLanes = 16;

}  // namespace kodawari::simd
