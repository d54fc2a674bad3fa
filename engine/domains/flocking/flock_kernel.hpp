#pragma once
// The flocking step written once (shaders/lib/flock_body.glsl) compiled as C++: GLM gives
// GLSL's vec3, ivec3 and functions, and a Kernel holds the buffers the GLSL reads as
// spans, so the body's accessors read the same data. The grid passes (flock_grid.comp's
// clear, count, scan, scatter) are build_grid() here: a counting sort in bird order.

#include <cstdint>
#include <span>
#include <vector>

#include <glm/glm.hpp>

#include <kodawari/shared/flocking.h>

#include "core/internal_api.hpp"

namespace kodawari::flocking::glsl {

// GLSL's names for the body (inside this namespace only).
using namespace glm;
using uint = std::uint32_t;
using gpu::FlockAgentGpu;
using gpu::FlockBirdGpu;
using gpu::FlockParamsGpu;
using gpu::FlockPerchGpu;
using gpu::FlockStateGpu;

inline vec3 kw_xyz(const gpu::vec4& v) { return vec3(v.x, v.y, v.z); }

// The grid's hash (lib/flock_hash.glsl), inline: one definition for every translation unit.
#define KW_FLOCK_FN inline
#include "lib/flock_hash.glsl"
#undef KW_FLOCK_FN

/// One frame's buffers, as flock_step.comp binds them.
struct Kernel {
    std::span<const FlockParamsGpu> flocks;
    std::span<const FlockBirdGpu> birds_in;
    std::span<const FlockStateGpu> states;  ///< this frame's slot
    std::span<const uint> buckets;          ///< start, count per bucket
    std::span<const uint> sorted;
    std::span<const FlockAgentGpu> agents_in;
    std::span<const FlockPerchGpu> perches_in;  ///< per bird (read only where a flock lands)

#define KW_XYZ(v) kw_xyz(v)
#define KW_INOUT(T) T&
    FlockParamsGpu kw_flock(uint f) const { return flocks[f]; }
    FlockBirdGpu kw_bird(uint i) const { return birds_in[i]; }
    FlockStateGpu kw_state(uint i) const { return states[i]; }
    uint kw_bucket_start(uint b) const { return buckets[2u * b]; }
    uint kw_bucket_count(uint b) const { return buckets[2u * b + 1u]; }
    uint kw_sorted(uint s) const { return sorted[s]; }
    // By index, as the reference has always read a candidate (the GPU reads the grid's
    // copy, whose w its scatter writes by the same flock_seen_as()).
    vec4 kw_point(uint s) const {
        const uint j = sorted[s];
        return vec4(kw_xyz(states[j].position), flock_seen_as(birds_in[j], flocks[birds_in[j].ids.x], states[j]));
    }
    FlockAgentGpu kw_agent(uint a) const { return agents_in[a]; }
#include "lib/flock_body.glsl"
#undef KW_INOUT
#undef KW_XYZ
};

}  // namespace kodawari::flocking::glsl

namespace kodawari::flocking {

/// The bucket table's size for `birds` birds: a power of two, at least twice the birds
/// (few collisions) and at least KW_FLOCK_SCAN_SIZE.
[[nodiscard]] KODAWARI_INTERNAL std::uint32_t bucket_count(std::uint32_t birds);

/// out[t] = glsl::flock_bucket((x[t], y[t], z[t]), inv_radius, mask) for t < n: the cpu
/// backend's, a vector of birds at a time (flock_grid_simd.cpp). Returns whether any
/// coordinate is NaN or infinite.
using BucketsFn = bool (*)(const float* x, const float* y, const float* z, std::size_t n, float inv_radius, std::uint32_t mask,
                           std::uint32_t* out);

/// BucketsFn compiled for the Highway target `target` (simd::Isa::target).
[[nodiscard]] KODAWARI_INTERNAL BucketsFn flock_buckets_kernel(std::int64_t target);

/// flock_grid.comp's passes on the CPU: `buckets` (2 per bucket: start, count) and
/// `sorted` (the birds by bucket, in bird order within one) for `states`, by index, on one
/// thread (cpu-reference's; tests').
KODAWARI_INTERNAL void build_grid(std::span<const gpu::FlockStateGpu> states, float inv_radius, std::uint32_t mask,
                                  std::vector<std::uint32_t>& cells, std::vector<std::uint32_t>& buckets,
                                  std::vector<std::uint32_t>& sorted);

/// The same grid for birds held in slot order (the cpu backend's: flock_cpu.cpp keeps each
/// bird's state at its slot of the last grid, so that a thread reads and writes the same
/// birds substep after substep): old slot t holds bird index[t] at (x[t], y[t], z[t]).
/// `buckets` are build_grid()'s of those birds, and `sorted` too where a position is NaN
/// or infinite; elsewhere a bucket's birds come in their old slots' order, not always by
/// index (the cpu backend's search finds the same neighbours in any order of them where
/// no distance is NaN, flock_search.hpp). `perm[s]` is the old slot of new slot s, `slot_of[i]` bird i's new slot (written here, on
/// one thread: two threads writing a bird each by index share cache lines), `cells[t]` old
/// slot t's bucket. The buckets are
/// found by `find` over `threads` threads' equal shares of the slots, the counting sort
/// on one.
KODAWARI_INTERNAL void build_grid_slots(const float* x, const float* y, const float* z, std::span<const std::uint32_t> index,
                                        float inv_radius, std::uint32_t mask, BucketsFn find, unsigned threads,
                                        std::vector<std::uint32_t>& cells, std::vector<std::uint32_t>& buckets,
                                        std::vector<std::uint32_t>& sorted, std::vector<std::uint32_t>& perm,
                                        std::vector<std::uint32_t>& slot_of);

}  // namespace kodawari::flocking
