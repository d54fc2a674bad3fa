// The flocking grid's bucket of a cell and of a position, written once for GLSL
// (flock_grid.comp, flock_step.comp) and C++ (engine/domains/flocking/flock_kernel.hpp):
// a cell of the search radius's size, placed in a power-of-two table by its Morton code
// (Morton 1966; the order Green 2010's particle grid sorts by), so that cells near in
// space are near in the table and in the grid's sorted order: a bird's 27 cells and the
// next birds' lie in a few runs of memory, where Teschner et al. 2003's hash (used until
// 2026-12) scattered them over the whole table, a cache miss each once the flock
// outgrows the caches (the cpu backend's search at a million birds: 616 -> 240 ns a
// bird, docs/performance.md). The code takes 10 bits an axis (cells 1 024 apart share
// them); the bits above the table's and those cells' blocks, hashed by Teschner's primes
// and mixed, are xor-ed in, so a wide flock's far cells spread over the table instead of
// piling into one bucket, and a compact one (within the table's span, no block crossed)
// keeps the plain code. Nothing depends on which cells share a bucket (the search keeps
// the k nearest by a total order). Unsigned arithmetic wraps the same way in both
// languages. At its end, which birds the grid shows the search at all (perches).
// KW_FLOCK_FN: nothing in GLSL, `inline` in C++ (a header's functions).
#ifndef KW_FLOCK_FN
#define KW_FLOCK_FN
#endif

// Bit i of v's low 10 bits to bit 3i.
KW_FLOCK_FN uint flock_spread3(uint v) {
    v &= 0x3FFu;
    v = (v | (v << 16u)) & 0x030000FFu;
    v = (v | (v << 8u)) & 0x0300F00Fu;
    v = (v | (v << 4u)) & 0x030C30C3u;
    v = (v | (v << 2u)) & 0x09249249u;
    return v;
}

// A 32-bit mix with mix(0) = 0 (lib/hash.glsl).
#define KW_HASH_FN KW_FLOCK_FN
#include "lib/hash.glsl"
KW_FLOCK_FN uint flock_mix(uint h) { return kw_lowbias32(h); }

// The hash's constants, named once for its copies on the cpu backend (flock_search_simd.cpp's
// 27 buckets at a time, flock_grid_simd.cpp's vector of birds at a time): a cell is offset
// by half a block of 2^10 cells, so a flock round the origin lies in one block, and its
// block's coordinates are hashed by Teschner et al.'s primes.
#ifndef KW_FLOCK_HALF_BLOCK
#define KW_FLOCK_HALF_BLOCK 512u
#define KW_FLOCK_BLOCK_BITS 10u
#define KW_FLOCK_PRIME_X 73856093u
#define KW_FLOCK_PRIME_Y 19349663u
#define KW_FLOCK_PRIME_Z 83492791u
// The largest float below 2^31: a cell index of at least this size is out of the int range.
#define KW_FLOCK_CELL_LIMIT 2147483520.0f
#endif

KW_FLOCK_FN uint flock_cell_bucket(ivec3 c, uint mask) {
    const uvec3 u = uvec3(c) + uvec3(KW_FLOCK_HALF_BLOCK);
    const uint morton = flock_spread3(u.x) | (flock_spread3(u.y) << 1u) | (flock_spread3(u.z) << 2u);
    const uvec3 block = u >> KW_FLOCK_BLOCK_BITS;
    const uint wrap = (morton & ~mask) ^ (block.x * KW_FLOCK_PRIME_X) ^ (block.y * KW_FLOCK_PRIME_Y) ^ (block.z * KW_FLOCK_PRIME_Z);
    return (morton ^ flock_mix(wrap)) & mask;
}

// A NaN, infinite or far position's cell (beyond the int range) is the range's lowest
// value, where x86's conversion has always put it: said here, since a float's conversion
// out of range is undefined in C++ (and stopped by the sanitizers) and in GLSL.
KW_FLOCK_FN ivec3 flock_cell(vec3 p, float inv_radius) {
    const vec3 c = floor(p * inv_radius);
    return ivec3(mix(vec3(-2147483648.0f), c, lessThan(abs(c), vec3(KW_FLOCK_CELL_LIMIT))));
}

// The cell d (-1 to 1 an axis) away from cell c, wrapping as unsigned arithmetic does: a
// NaN or infinite position's cell lies at the int range's end (x86's conversion gives
// its lowest value), where a signed overflow would be undefined in C++ (and stopped by
// the sanitizers). The same cells as c + d wherever that does not overflow.
KW_FLOCK_FN ivec3 flock_cell_near(ivec3 c, ivec3 d) { return ivec3(uvec3(c) + uvec3(d)); }

KW_FLOCK_FN uint flock_bucket(vec3 p, float inv_radius, uint mask) { return flock_cell_bucket(flock_cell(p, inv_radius), mask); }

// Perches (docs/flocking.md, "Perches"): a bird flocks from its first flocking frame
// (after its take-off from its perch) until it leaves the flock to land (its state's
// velocity.w); before and after, it flies its route (the bird domain, KW_MOTION_ROUTE), is
// not stepped (lib/flock_body.glsl's flock_route_motion()), and no other bird sees it: the
// grid's scatter gives it no flock. `flock` is the bird's flock's parameters this frame
// (counts.z: the frame stepped to).
KW_FLOCK_FN bool flock_flies(FlockBirdGpu bird, FlockParamsGpu flock, FlockStateGpu state) {
    return flock.counts.z >= bird.ids.y && state.velocity.w == 0.0f;
}

// A bird's flock as the search compares it (kw_point's w): none (-1) while it is not flying.
KW_FLOCK_FN float flock_seen_as(FlockBirdGpu bird, FlockParamsGpu flock, FlockStateGpu state) {
    return flock_flies(bird, flock, state) ? float(bird.ids.x) : -1.0f;
}
