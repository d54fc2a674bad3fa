#pragma once
/// @file
/// Backends of every kind, and the Vulkan device they can share (kodawari::vulkan).
///
/// The kind-dispatching factories live in the vulkan target, not in kodawari::sim with a
/// registry the vulkan target fills at static initialization: a static library drops
/// object files nothing references, so such a registration silently disappears from a
/// link, and whether make_bird_backend(Vulkan) worked would depend on link flags. Here
/// the dependency is a symbol: whoever calls these links kodawari::vulkan, and a program
/// that links kodawari::sim alone calls make_cpu_bird_backend() and friends (backend.hpp,
/// rod_backend.hpp, pose_backend.hpp), which make the CPU kinds.

#include <cstdint>
#include <memory>
#include <string>

#include "kodawari/core/api.hpp"
#include "kodawari/backends/backend.hpp"
#include "kodawari/backends/pose_backend.hpp"
#include "kodawari/core/result.hpp"
#include "kodawari/backends/rod_backend.hpp"

namespace kodawari {

/// Creates a bird backend. Vulkan fails with a readable reason when no loader, driver or
/// device is available.
[[nodiscard]] KODAWARI_API Result<std::unique_ptr<BirdBackend>> make_bird_backend(BackendKind kind,
                                                                                  const BackendOptions& options);
/// Creates a rod backend; Vulkan fails with a readable reason when no loader, driver or
/// device is available.
[[nodiscard]] KODAWARI_API Result<std::unique_ptr<RodBackend>> make_rod_backend(BackendKind kind,
                                                                                const BackendOptions& options);
/// Creates a pose backend; Vulkan fails with a readable reason when no loader, driver or
/// device is available.
[[nodiscard]] KODAWARI_API Result<std::unique_ptr<PoseBackend>> make_pose_backend(BackendKind kind,
                                                                                  const BackendOptions& options);

/// Opens a Vulkan device (`options.device`, `options.validation`) to share between
/// backends through BackendOptions::context, so that their buffers meet on one device:
/// e.g. the pose backends' matrices feed the rod backend's input there
/// (CrowdAnimator::write_inputs_on). A renderer has its own (Renderer::device_context()).
[[nodiscard]] KODAWARI_API Result<std::shared_ptr<compute::Device>> open_shared_device(const BackendOptions& options);
/// The device backend "auto" runs on (Simulation::create and the C API's AUTO): with no
/// device named, the best one that opens and is a GPU, or null with `cpu_reason` saying
/// why auto takes the cpu backend (no device opens, or it is a CPU: auto_passes_over());
/// with a device named, that one whatever its type, and its failure to open is the error
/// (never a reason to run elsewhere). `options.context`, when set, is returned as it is.
[[nodiscard]] KODAWARI_API Result<std::shared_ptr<compute::Device>> open_auto_device(const BackendOptions& options,
                                                                                        std::string& cpu_reason);

}  // namespace kodawari
