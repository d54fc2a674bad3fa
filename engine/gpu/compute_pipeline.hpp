#pragma once
// A compute kernel from the embedded SPIR-V with its descriptor set of storage buffers
// and push constants.

#include <cstdint>
#include <span>
#include <string_view>
#include <vector>

#include "gpu/gpu_buffer.hpp"

namespace kodawari::gpu {

/// SPIR-V of shaders/<name>.comp, compiled at build time (empty when unknown).
[[nodiscard]] std::span<const std::uint32_t> embedded_shader(std::string_view name);

class ComputePipeline {
public:
    /// Buffers of the given descriptor types (uniform or storage) at bindings 0..n-1,
    /// `push_bytes` of push constants, and 32-bit specialization constants with ids
    /// 0..m-1.
    [[nodiscard]] static Result<ComputePipeline> create(const VulkanContext& ctx, std::string_view shader,
                                                        std::span<const vk::DescriptorType> bindings, std::uint32_t push_bytes,
                                                        std::span<const std::uint32_t> specialization = {});

    ComputePipeline(ComputePipeline&&) noexcept = default;
    ComputePipeline& operator=(ComputePipeline&&) noexcept = default;
    ComputePipeline(const ComputePipeline&) = delete;
    ComputePipeline& operator=(const ComputePipeline&) = delete;

    /// Points binding i at buffers[i] (whole buffer).
    void bind_buffers(const VulkanContext& ctx, std::span<const GpuBuffer* const> buffers) const;
    /// Points binding i at buffers[i] (whole buffer): for buffers another owner keeps,
    /// such as a backend's state bound by the renderer.
    void bind_buffers(const VulkanContext& ctx, std::span<const vk::Buffer> buffers) const;

    /// Binds pipeline and set, pushes constants and dispatches.
    void dispatch(const vk::raii::CommandBuffer& cmd, std::span<const std::byte> push, std::uint32_t groups_x) const;

    /// The one-dispatch step of the rod and pose backends: a barrier after what earlier
    /// dispatches and copies wrote (the state or output this dispatch reads and
    /// overwrites), the dispatch between timestamps 0 and 1, then a barrier that makes
    /// its writes visible to the host (mapped buffers, after the fence) and to copies
    /// (staged readback).
    void dispatch_for_host(const VulkanContext& ctx, const vk::raii::CommandBuffer& cmd, std::span<const std::byte> push,
                           std::uint32_t groups_x) const;

private:
    ComputePipeline() = default;
    vk::raii::DescriptorSetLayout set_layout_{nullptr};
    vk::raii::PipelineLayout layout_{nullptr};
    vk::raii::ShaderModule module_{nullptr};
    vk::raii::Pipeline pipeline_{nullptr};
    vk::raii::DescriptorPool pool_{nullptr};
    vk::raii::DescriptorSet set_{nullptr};
    std::vector<vk::DescriptorType> types_;
};

}  // namespace kodawari::gpu
