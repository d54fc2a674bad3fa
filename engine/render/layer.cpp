#include "render/layer.hpp"

#include <algorithm>

#include "gpu/compute_vulkan.hpp"

namespace kodawari::render {

Result<compute::Buffer> storage_with(gpu::VulkanContext& ctx, std::span<const std::byte> bytes) {
    auto buffer = compute::Buffer::create(ctx, std::max<std::uint64_t>(bytes.size(), 16), compute::Usage::Storage);
    if (!buffer) return buffer.error();
    KW_TRY(compute::upload(ctx, buffer.value(), bytes));
    return buffer;
}

Result<void> store(gpu::VulkanContext& ctx, std::optional<compute::Buffer>& slot, std::span<const std::byte> bytes) {
    auto buffer = storage_with(ctx, bytes);
    if (!buffer) return buffer.error();
    slot.emplace(std::move(buffer).value());
    return {};
}

Result<gpu::GraphicsPipeline> layer_pipeline(const LayerTarget& target, std::string_view vertex, std::string_view fragment,
                                             std::uint32_t vertex_stride, std::uint32_t attributes, std::uint32_t storage_buffers,
                                             vk::PrimitiveTopology topology) {
    return gpu::GraphicsPipeline::create(
        target.ctx, target.pass, vertex, fragment, vertex_stride, attributes, sizeof(gpu::RenderPush),
        {.topology = topology, .depth = true, .samples = target.samples, .storage_buffers = storage_buffers});
}

Result<void> layer_pipeline_with_set(const LayerTarget& target, std::string_view vertex, std::string_view fragment,
                                     std::uint32_t vertex_stride, std::uint32_t attributes, std::uint32_t storage_buffers,
                                     std::optional<gpu::GraphicsPipeline>& pipeline, std::optional<gpu::BufferSet>& set) {
    auto created = layer_pipeline(target, vertex, fragment, vertex_stride, attributes, storage_buffers);
    if (!created) return created.error();
    pipeline.emplace(std::move(created).value());
    auto made = gpu::BufferSet::create(target.ctx, *pipeline);
    if (!made) return made.error();
    set.emplace(std::move(made).value());
    return {};
}

}  // namespace kodawari::render
