#pragma once
// The cpu backend's neighbour search (flock_search_simd.cpp): an implementation of its own,
// hand-tuned with Highway, of what shaders/lib/flock_body.glsl's flock_neighbours() finds
// (cpu-reference and vulkan run that one), held to it bit for bit: the same candidates,
// the same distance arithmetic, and a result (the k nearest by distance and index, a
// total order) that does not depend on the order candidates are visited in. A NaN
// distance (from a NaN or infinite position) is NaN on both, its sign not always the same.
//
// Why it is faster: the grid's birds are copied each substep into arrays in bucket order
// (SortedBirds, from the birds' states by slot of the last grid, SlotStates), so a cell's candidates are contiguous floats a vector compares at once
// (16 on AVX-512), where the reference reads each candidate's 64-byte parameters and
// 32-byte state by index; only the few that pass go through the scalar insertion. And
// each bird searches first within a bound from its k-th distance of last time
// (kBoundGrowth): the same k nearest, ranked from about 9 candidates instead of 20.

#include <cstdint>
#include <span>
#include <vector>

#include "core/internal_api.hpp"
#include "domains/flocking/flock_kernel.hpp"

namespace kodawari::flocking {

/// Birds' states by slot, as arrays (the cpu backend's: it keeps each bird's state at its
/// slot of the last grid, flock_cpu.cpp).
struct KODAWARI_INTERNAL SlotStates {
    std::vector<float> x, y, z, w;      ///< position (w: FlockStateGpu's)
    std::vector<float> vx, vy, vz, vw;  ///< velocity (w: FlockStateGpu's)

    void resize(std::size_t n);
    [[nodiscard]] gpu::FlockStateGpu at(std::size_t t) const {
        return {{x[t], y[t], z[t], w[t]}, {vx[t], vy[t], vz[t], vw[t]}};
    }
    void set(std::size_t t, const gpu::FlockStateGpu& s) {
        x[t] = s.position.x, y[t] = s.position.y, z[t] = s.position.z, w[t] = s.position.w;
        vx[t] = s.velocity.x, vy[t] = s.velocity.y, vz[t] = s.velocity.z, vw[t] = s.velocity.w;
    }
};

/// The grid's birds in its sorted order (slot s holds bird sorted[s], the grid's own
/// array, which the kernel reads as kw_sorted), as arrays padded with kSortedPad unused
/// slots so that a vector load past a bucket's end stays inside.
struct KODAWARI_INTERNAL SortedBirds {
    static constexpr std::size_t kSortedPad = 16;
    std::vector<float> x, y, z;
    std::vector<float> vx, vy, vz;
    std::vector<float> pw, vw;  ///< the state's position.w and velocity.w
    std::vector<float> flock;  ///< the bird's flock (exact as a float below 2^24); -1 while it is not flying (flock_seen_as())
    std::vector<std::uint32_t> index;  ///< the bird (the grid's `sorted`, padded)
    std::vector<std::uint32_t> slot_of;  ///< bird i's slot: index[slot_of[i]] == i (build_grid_slots() writes it)
    /// Slot s's bird's k-th distance^2 of last time (SearchArgs::bounds), or infinity.
    std::vector<float> bound;

    /// Fills the arrays for a new grid from birds held by slot (the cpu backend's): `from`
    /// (old slot t: bird from_index[t]) and build_grid_slots()'s `perm` (new slot s holds
    /// old slot perm[s]), on `threads` threads, each its equal share of the slots;
    /// `bound` from `last_bounds` by old slot (as the search wrote them), or infinity
    /// where empty. `from_index` must not be `index`.
    void fill(const SlotStates& from, std::span<const std::uint32_t> from_index, std::span<const std::uint32_t> perm,
                std::span<const gpu::FlockBirdGpu> birds, std::span<const gpu::FlockParamsGpu> flocks, unsigned threads,
                std::span<const float> last_bounds);
};

/// What one call of the search reads.
struct SearchArgs {
    const glsl::Kernel* kernel = nullptr;
    const SortedBirds* sorted = nullptr;
    std::uint32_t mask = 0;
    float inv_radius = 0.0f;
    /// Optional (null: none), a float a slot: written with the distance^2 of the k-th
    /// neighbour each bird found (infinity where it found fewer), which the next fill
    /// hands to SortedBirds::bound for the next search: read there as a hint only (any
    /// value gives the same lists; by slot, in the grid's order, so that a million birds'
    /// bounds are read and written in order). Null: no bound read either.
    float* bounds = nullptr;
};

/// A bird's first bound: its k-th distance^2 of last time times this (a distance 1.1
/// times as far: room for a substep's motion). At 10 000 starlings-dense birds 97% of
/// the birds search within it, seeing 8.9 candidates (20 within the radius), and 0.09%
/// find fewer than k there and search again.
inline constexpr float kBoundGrowth = 1.2f;

/// The buckets of the 27 cells round `home` in flock_neighbours()'s order (dz, dy, dx
/// from -1 to 1, x fastest): glsl::flock_cell_bucket() of each, bit for bit, with the
/// Morton code's parts computed once an axis.
KODAWARI_INTERNAL void flock_cell_buckets27(glm::ivec3 home, std::uint32_t mask, std::uint32_t out[27]);

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
