#pragma once
// The constructor of the CPU pose backends (kodawari::sim), used by make_cpu_pose_backend();
// the vulkan one is in device_backends.hpp.

#include <memory>

#include "kodawari/pose_backend.hpp"

namespace kodawari {

[[nodiscard]] std::unique_ptr<PoseBackend> new_cpu_pose_backend(bool reference, unsigned threads);

}  // namespace kodawari
