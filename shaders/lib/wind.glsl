// The air's velocity in a gusty wind (rods::WindField, docs/models.md "Wind"), written once
// for GLSL (shaders/rods_step.comp) and C++ (engine/rods/wind.cpp, which every CPU backend
// calls), so that no backend has its own noise. Integer hashing wraps the same way in both
// languages; the float part is a few dozen operations, so the GPU differs from the CPU
// only by its rounding (fused multiply-adds).
//
// The gusts are value noise (Perlin 1985's lattice noise with a quintic fade, Perlin
// 2002) in the horizontal position, carried along with the mean wind (Taylor's frozen
// turbulence: a gust travels across the crowd at the wind's speed), and in time, over
// cells of gust_size metres and gust_period seconds: three independent smooth values in
// [-1, 1], the vertical one halved, since near the ground vertical gusts are about half
// as strong as along-wind ones (Panofsky & Dutton, "Atmospheric Turbulence", 1984:
// sigma_w ~ 1.25 u* against sigma_u ~ 2.4 u*).
//
// KW_WIND_FN: nothing in GLSL, `inline` in C++. Float literals carry an f (GLSL accepts
// it, C++ needs it).
#ifndef KW_WIND_FN
#define KW_WIND_FN
#endif

// A 32-bit integer hash with good avalanche (lib/hash.glsl).
#define KW_HASH_FN KW_WIND_FN
#include "lib/hash.glsl"
KW_WIND_FN uint wind_hash(uint x) { return kw_lowbias32(x); }

// Three values in [-1, 1) at lattice point c.
KW_WIND_FN vec3 wind_lattice(ivec3 c, uint seed) {
    const uint h = wind_hash(uint(c.x) ^ wind_hash(uint(c.y) ^ wind_hash(uint(c.z) ^ wind_hash(seed))));
    const uint h1 = wind_hash(h ^ 0x68e31da4u);
    const uint h2 = wind_hash(h ^ 0xb5297a4du);
    // 24 bits each: exact in a float.
    return vec3(float(h >> 8u), float(h1 >> 8u), float(h2 >> 8u)) * (2.0f / 16777216.0f) - vec3(1.0f);
}

// Value noise at q, smooth (C2) everywhere: the lattice values blended by the quintic
// fade 6t^5 - 15t^4 + 10t^3 along each axis.
KW_WIND_FN vec3 wind_noise(vec3 q, uint seed) {
    const vec3 cell = floor(q);
    const vec3 f = q - cell;
    const vec3 u = f * f * f * (f * (f * 6.0f - vec3(15.0f)) + vec3(10.0f));
    const ivec3 c = ivec3(cell);
    const vec3 x00 = mix(wind_lattice(c, seed), wind_lattice(c + ivec3(1, 0, 0), seed), u.x);
    const vec3 x10 = mix(wind_lattice(c + ivec3(0, 1, 0), seed), wind_lattice(c + ivec3(1, 1, 0), seed), u.x);
    const vec3 x01 = mix(wind_lattice(c + ivec3(0, 0, 1), seed), wind_lattice(c + ivec3(1, 0, 1), seed), u.x);
    const vec3 x11 = mix(wind_lattice(c + ivec3(0, 1, 1), seed), wind_lattice(c + ivec3(1, 1, 1), seed), u.x);
    return mix(mix(x00, x10, u.y), mix(x01, x11, u.y), u.z);
}

// The air's velocity (m/s) at world position p and time t (s) in a field of mean velocity
// `mean`, gust strength `gust` (a fraction of the mean speed), 1 / gust_period
// (`inv_period`, 1/s), 1 / gust_size (`inv_size`, 1/m) and `seed`:
//   w = mean + gust |mean| n((p_x - mean_x t) / size, (p_z - mean_z t) / size, t / period)
// with n's vertical component halved (above).
KW_WIND_FN vec3 wind_air_velocity(vec3 mean, float gust, float inv_period, float inv_size, uint seed, vec3 p, float t) {
    if (gust == 0.0f) return mean;
    const vec3 carried = p - mean * t;
    const vec3 n = wind_noise(vec3(carried.x * inv_size, carried.z * inv_size, t * inv_period), seed);
    return mean + (gust * length(mean)) * vec3(n.x, 0.5f * n.z, n.y);
}
