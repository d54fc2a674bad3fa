#pragma once
// Graphics pieces for the renderer (engine/render/): images with their memory and view,
// and pipelines of the embedded vertex + fragment shaders with one vertex layout.

#include <cstdint>
#include <string_view>

#include "gpu/vulkan_context.hpp"

namespace kodawari::gpu {

/// A 2D image in device-local memory with one view of it.
class GpuImage {
public:
    [[nodiscard]] static Result<GpuImage> create(const VulkanContext& ctx, std::uint32_t width, std::uint32_t height,
                                                 vk::Format format, vk::ImageUsageFlags usage, vk::ImageAspectFlags aspect);

    GpuImage(GpuImage&&) noexcept = default;
    GpuImage& operator=(GpuImage&&) noexcept = default;
    GpuImage(const GpuImage&) = delete;
    GpuImage& operator=(const GpuImage&) = delete;
    ~GpuImage() = default;

    [[nodiscard]] vk::Image handle() const { return *image_; }
    [[nodiscard]] vk::ImageView view() const { return *view_; }

private:
    GpuImage() = default;
    vk::raii::DeviceMemory memory_{nullptr};  // declared first: destroyed after the image and view
    vk::raii::Image image_{nullptr};
    vk::raii::ImageView view_{nullptr};
};

/// What differs between the renderer's pipelines.
struct GraphicsPipelineOptions {
    vk::PrimitiveTopology topology = vk::PrimitiveTopology::eTriangleList;
    bool depth = true;  ///< depth test (less) and write; off: drawn over what is there
};

/// A pipeline of the embedded `vertex` and `fragment` shaders for `render_pass`
/// subpass 0: one vertex buffer of `vertex_stride`-byte vertices whose attributes are
/// `attributes` vec4s at locations 0.. (offsets 0, 16, ...), no culling, `push_bytes`
/// of push constants seen by both stages, viewport and scissor dynamic.
class GraphicsPipeline {
public:
    [[nodiscard]] static Result<GraphicsPipeline> create(const VulkanContext& ctx, vk::RenderPass render_pass,
                                                         std::string_view vertex, std::string_view fragment,
                                                         std::uint32_t vertex_stride, std::uint32_t attributes,
                                                         std::uint32_t push_bytes, const GraphicsPipelineOptions& options);

    GraphicsPipeline(GraphicsPipeline&&) noexcept = default;
    GraphicsPipeline& operator=(GraphicsPipeline&&) noexcept = default;
    GraphicsPipeline(const GraphicsPipeline&) = delete;
    GraphicsPipeline& operator=(const GraphicsPipeline&) = delete;
    ~GraphicsPipeline() = default;

    [[nodiscard]] vk::Pipeline handle() const { return *pipeline_; }
    [[nodiscard]] vk::PipelineLayout layout() const { return *layout_; }

private:
    GraphicsPipeline() = default;
    vk::raii::PipelineLayout layout_{nullptr};
    vk::raii::ShaderModule vertex_{nullptr};
    vk::raii::ShaderModule fragment_{nullptr};
    vk::raii::Pipeline pipeline_{nullptr};
};

}  // namespace kodawari::gpu
