#pragma once
// Constructors of the concrete pose backends, used by make_pose_backend().

#include <memory>

#include "kodawari/pose_backend.hpp"

namespace kodawari {

[[nodiscard]] std::unique_ptr<PoseBackend> make_cpu_pose_backend(bool reference, unsigned threads);
[[nodiscard]] Result<std::unique_ptr<PoseBackend>> make_vulkan_pose_backend(const BackendOptions& options);

}  // namespace kodawari
