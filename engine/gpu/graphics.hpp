#pragma once
// Graphics pieces for the renderer (engine/render/): images with their memory and view,
// and pipelines of the embedded vertex + fragment shaders with one vertex layout.

#include <cstdint>
#include <span>
#include <string_view>

#include "gpu/compute_vulkan.hpp"
#include "core/internal_api.hpp"

namespace kodawari::gpu {

/// A 2D image in device-local memory with one view of it.
class KODAWARI_INTERNAL GpuImage {
public:
    [[nodiscard]] static Result<GpuImage> create(const VulkanContext& ctx, std::uint32_t width, std::uint32_t height,
                                                 vk::Format format, vk::ImageUsageFlags usage, vk::ImageAspectFlags aspect,
                                                 vk::SampleCountFlagBits samples = vk::SampleCountFlagBits::e1);

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
    /// Samples per pixel: the render pass's attachments' (multisampled: anti-aliased edges).
    vk::SampleCountFlagBits samples = vk::SampleCountFlagBits::e1;
    /// Alpha blending (source alpha over what is there) and no depth writes: translucent
    /// overlays such as ground shadows, drawn after the opaque geometry.
    bool blend = false;
    /// Storage buffers the vertex shader reads, at set 0, bindings 0..n-1 (the layers
    /// drawn from device buffers); bound with a BufferSet.
    std::uint32_t storage_buffers = 0;
};

/// A pipeline of the embedded `vertex` and `fragment` shaders for `render_pass`
/// subpass 0: one vertex buffer of `vertex_stride`-byte vertices whose attributes are
/// `attributes` vec4s at locations 0.. (offsets 0, 16, ...; none: no vertex buffer), no
/// culling, `push_bytes` of push constants seen by both stages, viewport and scissor
/// dynamic.
class KODAWARI_INTERNAL GraphicsPipeline {
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
    /// The layout of set 0 (GraphicsPipelineOptions::storage_buffers; null without).
    [[nodiscard]] vk::DescriptorSetLayout set_layout() const { return *set_layout_; }
    [[nodiscard]] std::uint32_t storage_buffers() const { return storage_buffers_; }

private:
    GraphicsPipeline() = default;
    vk::raii::DescriptorSetLayout set_layout_{nullptr};
    vk::raii::PipelineLayout layout_{nullptr};
    vk::raii::ShaderModule vertex_{nullptr};
    vk::raii::ShaderModule fragment_{nullptr};
    vk::raii::Pipeline pipeline_{nullptr};
    std::uint32_t storage_buffers_ = 0;
};

/// A descriptor set of a graphics pipeline's storage buffers (its own pool).
class KODAWARI_INTERNAL BufferSet {
public:
    [[nodiscard]] static Result<BufferSet> create(const VulkanContext& ctx, const GraphicsPipeline& pipeline);

    BufferSet(BufferSet&&) noexcept = default;
    BufferSet& operator=(BufferSet&&) noexcept = default;
    BufferSet(const BufferSet&) = delete;
    BufferSet& operator=(const BufferSet&) = delete;
    ~BufferSet() = default;

    /// Points binding i at buffers[i]: one per binding of the pipeline. Only between
    /// frames (no submission that uses the set may be pending).
    void bind(const VulkanContext& ctx, std::span<const BufferRange> buffers);
    [[nodiscard]] vk::DescriptorSet handle() const { return *set_; }

private:
    BufferSet() = default;
    vk::raii::DescriptorPool pool_{nullptr};
    vk::raii::DescriptorSet set_{nullptr};
    std::uint32_t count_ = 0;
};

}  // namespace kodawari::gpu
