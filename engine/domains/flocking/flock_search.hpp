#pragma once
// The cpu backend's neighbour search (flock_search_simd.cpp): an implementation of its own,
// hand-tuned with Highway, of what shaders/lib/flock_body.glsl's flock_neighbours() finds
// (cpu-reference and vulkan run that one), held to it bit for bit: the same candidates,
// the same distance arithmetic, and a result (the k nearest by distance and index, a
// total order) that does not depend on the order candidates are visited in. A NaN
// distance (from a NaN or infinite position) is NaN on both, its sign not always the same.
//
// Why it is faster: the grid's birds are copied each substep into arrays in bucket order
// (SortedBirds), so a cell's candidates are contiguous floats a vector compares at once
// (16 on AVX-512), where the reference reads each candidate's 64-byte parameters and
// 32-byte state by index; only the few that pass go through the scalar insertion.

#include <cstdint>
#include <span>
#include <vector>

#include "core/internal_api.hpp"
#include "domains/flocking/flock_kernel.hpp"

namespace kodawari::flocking {

/// The grid's birds in its sorted order (slot s holds bird sorted[s], the grid's own
/// array, which the kernel reads as kw_sorted), as arrays padded with kSortedPad unused
/// slots so that a vector load past a bucket's end stays inside.
struct KODAWARI_INTERNAL SortedBirds {
    static constexpr std::size_t kSortedPad = 16;
    std::vector<float> x, y, z;
    std::vector<float> vx, vy, vz;
    std::vector<float> flock;  ///< the bird's flock (exact as a float below 2^24); -1 while it is not flying (flock_seen_as())
    std::vector<std::uint32_t> index;  ///< the bird (the grid's `sorted`, padded)
    std::vector<std::uint32_t> slot_of;  ///< bird i's slot: index[slot_of[i]] == i

    /// Fills the arrays from this substep's states, flocks and grid (build_grid()'s
    /// `sorted`), on `threads` threads.
    void fill(std::span<const gpu::FlockStateGpu> states, std::span<const gpu::FlockBirdGpu> birds,
              std::span<const gpu::FlockParamsGpu> flocks, std::span<const std::uint32_t> sorted, unsigned threads = 1);
};

/// What one call of the search reads.
struct SearchArgs {
    const glsl::Kernel* kernel = nullptr;
    const SortedBirds* sorted = nullptr;
    std::uint32_t mask = 0;
    float inv_radius = 0.0f;
};

/// Fills out[n] with the neighbours of the bird in grid slot first_slot + n (kw_sorted),
/// n < count: birds in the grid's order, so that the birds of one cell come
/// together, share its 27 buckets' candidates, and are read in order. What
/// flock_neighbours() gives each, bit for bit.
using SearchFn = void (*)(const SearchArgs& args, std::uint32_t first_slot, std::uint32_t count,
                          glsl::Kernel::FlockNeighbours* out);

/// The search compiled for the Highway target `target` (simd::Isa::target).
[[nodiscard]] KODAWARI_INTERNAL SearchFn flock_search_kernel(std::int64_t target);

/// The most candidates a bird may see for the search to pick its nearest by rank; past it
/// (a dense flock, a metric radius) the search offers them to flock_offer() one by one.
/// The same lists either way: tests/flocking/test_flock_simd.cpp covers both.
inline constexpr std::size_t kSearchRankedMost = 64;

}  // namespace kodawari::flocking
