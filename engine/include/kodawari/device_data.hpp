#pragma once
/// @file
/// What a backend keeps on its device, for other GPU work on that device (the renderer
/// draws from it, the crowd animator writes the rod input from the pose matrices) without
/// a copy back to the host (issue 5). One typed interface for every backend family,
/// naming no graphics-API type: buffers are the compute layer's (engine/compute/).

#include <cstdint>

#include "kodawari/api.hpp"

namespace kodawari {

namespace gpu {
class VulkanContext;
}
namespace compute {
class Buffer;
}

/// The buffers a backend may keep on its device; element layouts in shaders/shared/.
enum class DeviceBuffer : std::uint8_t {
    BirdPoses,       ///< BirdPoseGpu: the bird backend's ring of frame slots
    RodChainStates,  ///< RodChainStateGpu per chain (root.position)
    RodMotion,       ///< RodJointMotionGpu per joint (x, relative to the root)
    RodSpin,         ///< RodJointSpinGpu per joint (q, the particle's orientation)
    RodReference,    ///< RodTransformGpu per character: this frame's input
    RodRoots,        ///< RodTransformGpu per chain: this frame's input
    RodColliders,    ///< RodColliderGpu: this frame's input
    PoseWorld,       ///< PoseMatrixGpu, items (instances) x per_item (nodes), instance-major
    RodKeys,         ///< RodTransformGpu per key source (RodFrame::keys): this frame's input
    RodCenters,      ///< RodTransformGpu per center frame (RodFrame::centers): this frame's input
};

/// Where a named buffer's current data is.
struct DeviceSpan {
    const compute::Buffer* buffer = nullptr;  ///< null: the backend keeps no such buffer (now)
    std::uint64_t first = 0;                  ///< the first element of the current data (BirdPoses: bird 0 of the last frame)
    std::uint32_t items = 0;                  ///< birds, chains, joints, instances
    std::uint32_t per_item = 1;               ///< elements per item (PoseWorld: nodes)
};

/// A backend's data on its device (BirdBackend, RodBackend, PoseBackend::device_data()).
class KODAWARI_API DeviceData {
public:
    virtual ~DeviceData() = default;
    /// The device the buffers live on: compare with a renderer's before drawing from them.
    [[nodiscard]] virtual const gpu::VulkanContext& context() const = 0;
    /// A named buffer; {} when this backend has none (another family's name, or not loaded).
    [[nodiscard]] virtual DeviceSpan buffer(DeviceBuffer name) const = 0;

protected:
    DeviceData() = default;
    DeviceData(const DeviceData&) = default;
    DeviceData& operator=(const DeviceData&) = default;
};

}  // namespace kodawari
