#pragma once
// The per-lane scalar steps of the SIMD kernels: transcendental functions the kernels
// need once per chain or per bird (not per solver iteration), computed with the very code
// and library calls of the CPU reference, so that those results are the reference's bits.
// Plain functions in a plain translation unit: the kernels' own code is compiled once per
// instruction set and must not instantiate the reference's inline functions (glm, <cmath>
// templates) under a target attribute.

#include <cstddef>

#include <kodawari/shared/birds.h>

namespace kodawari::simd {

/// out[i] = std::pow(base[i], exponent) for i < count (rods::view_weights).
void pow_lanes(const float* base, float exponent, float* out, std::size_t count);

/// Quaternions as four rows of `count` floats (x, y, z, w; row stride `stride`), each
/// replaced by the rotation by `fraction` of its angle, the short way: solver.cpp's
/// partial() (the rest-shape root interpolation and partial momentum suppression).
void partial_lanes(float* q, std::size_t stride, float fraction, std::size_t count);

/// The seed's bank rule (SPEC B.4) of birds::body_frame, lane by lane: attitude velocity
/// and acceleration as rows of `count` floats (vx, vy, vz, ax, ay, az; stride `stride`)
/// in, the bank factor as rows (x, y, z, w) out.
void seed_bank_lanes(const gpu::FlightUniforms& uniforms, const float* motion, std::size_t stride, float* rotation,
                              std::size_t count);

/// The diagnostics' bank of flight.cpp step_bird(), 2 atan2(z, w) of the Body's bank
/// quaternion: rows z and w in, `count` angles out.
void half_angle_lanes(const float* z, const float* w, float* angle, std::size_t count);

/// birds::attitude() lane by lane (the diagnostics' yaw, climb and bank): rows as above in,
/// rows (yaw, pitch, bank) out.
void attitude_lanes(const gpu::FlightUniforms& uniforms, const float* motion, std::size_t stride, float* angles,
                    std::size_t count);

}  // namespace kodawari::simd
