#pragma once
// The constructors of the CPU pose backends (cpu-reference: cpu_poses.cpp; cpu: simd_poses.cpp) (kodawari::sim), used by make_cpu_pose_backend();
// the vulkan one is in device_backends.hpp.

#include <memory>

#include "kodawari/backends/pose_backend.hpp"
#include "simd/isa.hpp"

namespace kodawari {

[[nodiscard]] std::unique_ptr<PoseBackend> new_reference_pose_backend();
[[nodiscard]] std::unique_ptr<PoseBackend> new_simd_pose_backend(simd::Isa isa, unsigned threads);

}  // namespace kodawari
