#pragma once
// The cpu backend's rules (flock_rules_simd.cpp): shaders/lib/flock_body.glsl's
// flock_rules() for a vector of birds at once, hand-written with Highway, held to the body
// bit for bit: the same IEEE operations in the same order (GLM's dot is (x + y) + z, its
// min, max and clamp are comparisons, not minps/maxps; no fused multiply-add), each
// branch a mask (NaN deciding each comparison as the body's C++ does), the exponential
// the same libm call lane by lane. cpu-reference and vulkan run the body. A NaN result is
// NaN on both, its sign not always the same (the compiler orders a scalar operation's
// operands as it likes, and x86 gives the first NaN operand's).
//
// Why it is faster: a bird's rules take about 8 divisions and 2 square roots per
// neighbour, which one scalar divider does one after the other (about 200 ns a bird at
// 7 neighbours, half the cpu backend's time at 10 000 birds once its search was
// tuned); a vector divides 16 lanes at once on AVX-512.

#include <cstdint>

#include "core/internal_api.hpp"
#include "domains/flocking/flock_kernel.hpp"
#include "domains/flocking/flock_search.hpp"

namespace kodawari::flocking {

/// What one call of the rules reads beside the birds' neighbours.
struct RulesArgs {
    const glsl::Kernel* kernel = nullptr;
    /// The grid's birds in its order: their positions and velocities, and their
    /// neighbours' (by slot_of), read there, in order, rather than by index.
    const SortedBirds* sorted = nullptr;
    std::uint32_t agents = 0;  ///< the frame's agents (kernel->agents_in)
    float dt = 0.0f;
};

/// out[m] = kernel.flock_rules(kw_sorted(first_slot + m), found[m], agents, dt) for
/// m < count: the birds in the grid's order, as the search gives their neighbours.
using RulesFn = void (*)(const RulesArgs& args, std::uint32_t first_slot, std::uint32_t count,
                         const glsl::Kernel::FlockNeighbours* found, glsl::Kernel::FlockStep* out);

/// The rules compiled for the Highway target `target` (simd::Isa::target).
[[nodiscard]] KODAWARI_INTERNAL RulesFn flock_rules_kernel(std::int64_t target);

}  // namespace kodawari::flocking
