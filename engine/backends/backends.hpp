#pragma once
// Constructors of the CPU backends (kodawari::sim), used by make_cpu_bird_backend() and
// make_cpu_rod_backend(): cpu-reference (cpu_*.cpp, engine/birds and engine/rods on one
// thread) and cpu (simd_*.cpp, the vectorized kernels of engine/simd on `threads`
// threads); the vulkan ones are in device_backends.hpp.

#include <algorithm>
#include <memory>

#include "kodawari/backends/backend.hpp"
#include "kodawari/backends/rod_backend.hpp"
#include "simd/isa.hpp"

namespace kodawari {

[[nodiscard]] std::unique_ptr<BirdBackend> new_reference_bird_backend();
[[nodiscard]] std::unique_ptr<RodBackend> new_reference_rod_backend();
[[nodiscard]] std::unique_ptr<BirdBackend> new_simd_bird_backend(simd::Isa isa, unsigned threads);
[[nodiscard]] std::unique_ptr<RodBackend> new_simd_rod_backend(simd::Isa isa, unsigned threads);

/// Whether any of a frame's wind fields moves the air: a calm field (velocity 0) moves
/// nothing whatever its gusts, which scale with the mean speed, so a backend may take the
/// air as 0 everywhere (the same bits). The rod backends' one test of it.
inline bool moving_air(const rods::RodFrame& frame) {
    return std::any_of(frame.winds.begin(), frame.winds.end(),
                       [](const rods::WindField& w) { return w.velocity != glm::vec3(0.0f); });
}

}  // namespace kodawari
