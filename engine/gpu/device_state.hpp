#pragma once
// Where the vulkan backends keep what the renderer draws (issue 5: the viewer draws from
// the simulation's buffers on the device they were computed on, with no copy back).

#include <cstdint>
#include <memory>

#include <vulkan/vulkan_raii.hpp>

namespace kodawari::gpu {

class VulkanContext;

/// The vulkan rod backend's state after its last load() or step().
struct RodDeviceState {
    const VulkanContext* context = nullptr;  ///< the device the buffers live on
    vk::Buffer chain_states;                 ///< RodChainStateGpu per chain (root.position)
    vk::Buffer motion;                       ///< RodJointMotionGpu per joint (x, relative to the root)
    vk::Buffer spin;                         ///< RodJointSpinGpu per joint (q, the particle's orientation)
    vk::Buffer reference;                    ///< RodTransformGpu per character: this frame's input
    vk::Buffer roots;                        ///< RodTransformGpu per chain: this frame's input
    vk::Buffer colliders;                    ///< RodColliderGpu: this frame's input
};

/// Records kernels that write part of a step's kinematic input where the vulkan rod
/// backend keeps it (RodBackend::set_input_writer): after the frame's input has been
/// uploaded, before the step's dispatch, in the same submission.
class RodInputWriter {
public:
    virtual ~RodInputWriter() = default;
    virtual void record(const vk::raii::CommandBuffer& cmd, const RodDeviceState& state) const = 0;
};

/// The vulkan pose backend's world matrices after its last evaluate().
struct PoseDeviceWorld {
    const VulkanContext* context = nullptr;
    vk::Buffer world;              ///< PoseMatrixGpu, instances x nodes, instance-major
    std::uint32_t instances = 0;
    std::uint32_t nodes = 0;
};

/// The vulkan bird backend's poses of the last simulated frame.
struct BirdDevicePoses {
    const VulkanContext* context = nullptr;
    vk::Buffer poses;        ///< BirdPoseGpu, the backend's ring of frame slots
    std::uint32_t first = 0; ///< index of bird 0's pose of that frame
};

}  // namespace kodawari::gpu
