#pragma once
// The compute layer's Vulkan implementation, as the engine's own Vulkan code sees it: the
// handles behind kodawari/vulkan/compute.hpp's Buffer, Recording and Kernel, and the device as a
// gpu::VulkanContext. The renderer's graphics, the domains' render layers and the
// embedding entry points use these; a domain's compute code needs none of them.

#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <string_view>

#include <vulkan/vulkan_raii.hpp>

#include "core/internal_api.hpp"
#include "gpu/vulkan_context.hpp"
#include "kodawari/vulkan/compute.hpp"

namespace kodawari::gpu {
/// SPIR-V of shaders/<name>, compiled at build time (empty when unknown;
/// cmake/embedded_shaders.cpp.in defines it).
[[nodiscard]] std::span<const std::uint32_t> embedded_shader(std::string_view name);
}  // namespace kodawari::gpu

namespace kodawari::compute {

struct Buffer::Native {
    vk::raii::DeviceMemory memory{nullptr};
    vk::raii::Buffer buffer{nullptr};
};

/// A command slot: the command buffer (owned, or an application's let go of unfreed) and
/// the fence of its submission.
struct Recording::Native {
    gpu::CommandSlot slot;
};

struct Kernel::Native {
    const gpu::VulkanContext* device = nullptr;
    vk::raii::DescriptorSetLayout set_layout{nullptr};
    vk::raii::PipelineLayout layout{nullptr};
    vk::raii::ShaderModule module{nullptr};
    vk::raii::Pipeline pipeline{nullptr};
    vk::raii::DescriptorPool pool{nullptr};
    vk::raii::DescriptorSet set{nullptr};
    std::vector<vk::DescriptorType> types;
};

using gpu::embedded_shader;
using gpu::guard;

}  // namespace kodawari::compute

namespace kodawari::gpu {

/// The device as its implementation: every compute::Device is a VulkanContext.
[[nodiscard]] inline VulkanContext& vulkan(compute::Device& device) { return static_cast<VulkanContext&>(device); }
[[nodiscard]] inline const VulkanContext& vulkan(const compute::Device& device) {
    return static_cast<const VulkanContext&>(device);
}
[[nodiscard]] inline std::shared_ptr<VulkanContext> vulkan(const std::shared_ptr<compute::Device>& device) {
    return std::static_pointer_cast<VulkanContext>(device);
}

/// The Vulkan buffer of a compute::Buffer (descriptor sets, vertex bindings, copies).
[[nodiscard]] inline vk::Buffer vk_buffer(const compute::Buffer& buffer) { return *buffer.native().buffer; }
/// The command buffer a compute::Recording records into.
[[nodiscard]] inline const vk::raii::CommandBuffer& vk_commands(const compute::Recording& recording) {
    return recording.native().slot.cmd;
}

/// A compute::Recording into `cmd`, a command buffer the caller owns (an application's,
/// or the renderer's frame): nothing is submitted, waited for or freed here. Uploads go
/// through `staging`'s current slot (null: the recording uploads nothing).
[[nodiscard]] KODAWARI_INTERNAL compute::Recording borrow(compute::Device& device, VkCommandBuffer cmd,
                                                         compute::StagingRing* staging);

/// compute::Kernel::dispatch into a Vulkan command buffer the compute layer does not own:
/// the renderer's frame, which also waits on and signals a window's semaphores.
KODAWARI_INTERNAL void dispatch(const compute::Kernel& kernel, const vk::raii::CommandBuffer& cmd, std::span<const std::byte> push,
                                std::uint32_t groups_x);

/// A range of a Vulkan buffer bound to a descriptor (the renderer's graphics sets; a
/// kernel binding of a buffer the compute layer does not own, an application's).
struct BufferRange {
    vk::Buffer buffer;
    vk::DeviceSize offset = 0;
    vk::DeviceSize size = VK_WHOLE_SIZE;
};

/// compute::Kernel::bind for ranges of Vulkan buffers, some of them not the compute
/// layer's (the application's matrices, kodawari/vulkan/vulkan_embed.hpp's set_matrix_input).
KODAWARI_INTERNAL void bind(const compute::Kernel& kernel, std::span<const BufferRange> ranges);

}  // namespace kodawari::gpu
