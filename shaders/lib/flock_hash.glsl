// The flocking grid's bucket of a cell and of a position, written once for GLSL
// (flock_grid.comp, flock_step.comp) and C++ (engine/domains/flocking/flock_kernel.hpp):
// a cell of the search radius's size, hashed (Teschner et al. 2003's primes) into a
// power-of-two table. Unsigned arithmetic wraps the same way in both languages.
// KW_FLOCK_FN: nothing in GLSL, `inline` in C++ (a header's functions).
#ifndef KW_FLOCK_FN
#define KW_FLOCK_FN
#endif

KW_FLOCK_FN uint flock_cell_bucket(ivec3 c, uint mask) {
    return ((uint(c.x) * 73856093u) ^ (uint(c.y) * 19349663u) ^ (uint(c.z) * 83492791u)) & mask;
}

KW_FLOCK_FN ivec3 flock_cell(vec3 p, float inv_radius) { return ivec3(floor(p * inv_radius)); }

KW_FLOCK_FN uint flock_bucket(vec3 p, float inv_radius, uint mask) { return flock_cell_bucket(flock_cell(p, inv_radius), mask); }
