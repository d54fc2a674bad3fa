#pragma once
// Constructors of the CPU backends (kodawari::sim), used by make_cpu_bird_backend() and
// make_cpu_rod_backend(): cpu-reference (cpu_*.cpp, engine/birds and engine/rods on one
// thread) and cpu (simd_*.cpp, the vectorized kernels of engine/simd on `threads`
// threads); the vulkan ones are in device_backends.hpp.

#include <memory>

#include "kodawari/backend.hpp"
#include "kodawari/rod_backend.hpp"
#include "simd/isa.hpp"

namespace kodawari {

[[nodiscard]] std::unique_ptr<BirdBackend> new_reference_bird_backend();
[[nodiscard]] std::unique_ptr<RodBackend> new_reference_rod_backend();
[[nodiscard]] std::unique_ptr<BirdBackend> new_simd_bird_backend(simd::Isa isa, unsigned threads);
[[nodiscard]] std::unique_ptr<RodBackend> new_simd_rod_backend(simd::Isa isa, unsigned threads);

}  // namespace kodawari
