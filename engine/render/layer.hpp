#pragma once
// What a domain draws from its own device buffers (issue 31): a render::Layer records its
// draws into the renderer's pass every frame, reading the domain's buffers where they are
// (its vulkan backend's own when they share the renderer's device: nothing is read back).
// The renderer keeps its layers by name and draws them in their order; it names no domain
// (Jolt's render features, Box2D's debug draw for what needs no device buffer:
// kodawari/render/draw.hpp). A domain makes its layer at the first call that needs it
// (layer_of()) with its own pipelines (layer_pipeline()) and shaders.

#include <bit>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <string_view>
#include <vector>

#include <kodawari/shared/render.h>

#include "gpu/compute_vulkan.hpp"
#include "gpu/graphics.hpp"
#include "kodawari/render/renderer.hpp"

namespace kodawari::render {

/// What a layer's pipelines are made for, and the device its buffers live on.
struct LayerTarget {
    gpu::VulkanContext& ctx;
    vk::RenderPass pass;
    vk::SampleCountFlagBits samples;
};

/// One frame as a layer records it.
struct LayerFrame {
    gpu::RenderPush push;  ///< the camera and the light (push.draw.w: the projection)
    float rows_scale;      ///< image rows / 720 within [0.5, 2]: minimum sizes in pixels scale by it
    bool joints;           ///< RendererOptions::joints
};

/// What a domain draws from device buffers.
class Layer {
public:
    virtual ~Layer() = default;
    /// Draw nothing from now on (Renderer::clear_layers()).
    [[nodiscard]] virtual Result<void> clear(gpu::VulkanContext& ctx) = 0;
    /// Compute work the draws read (outside the render pass); the renderer's barrier from
    /// compute to the vertex shaders follows.
    virtual void record_compute(const vk::raii::CommandBuffer& /*cmd*/) const {}
    /// The draws, inside the render pass (depth tested, before translucent shadows).
    virtual void record(const vk::raii::CommandBuffer& cmd, const LayerFrame& frame) const = 0;
};

using LayerFactory = std::function<Result<std::unique_ptr<Layer>>(const LayerTarget&)>;

/// `renderer`'s layer named `name`, made by `make` at the first call. Layers are drawn by
/// `order`, then by name (the same frame draws the same way every time).
[[nodiscard]] Result<Layer*> layer(Renderer& renderer, std::string_view name, int order, const LayerFactory& make);
/// The layer named `name`, or null before the first layer() of that name.
[[nodiscard]] const Layer* find_layer(const Renderer& renderer, std::string_view name);
/// The renderer's device (what layers upload to and bind).
[[nodiscard]] gpu::VulkanContext& layer_context(Renderer& renderer);

/// layer() for a layer type made by `L::create(const LayerTarget&)`.
template <typename L>
[[nodiscard]] Result<L*> layer_of(Renderer& renderer, std::string_view name, int order) {
    auto found = layer(renderer, name, order, [](const LayerTarget& target) -> Result<std::unique_ptr<Layer>> {
        auto made = L::create(target);
        if (!made) return made.error();
        return std::unique_ptr<Layer>(std::make_unique<L>(std::move(made).value()));
    });
    if (!found) return found.error();
    return static_cast<L*>(found.value());
}

/// A vector's bytes, as uploads take them.
template <typename T>
[[nodiscard]] std::span<const std::byte> bytes_of(const std::vector<T>& v) {
    return std::as_bytes(std::span<const T>(v));
}
/// A float's bits, as RenderPush::draw carries layer parameters.
[[nodiscard]] inline std::uint32_t float_bits(float value) { return std::bit_cast<std::uint32_t>(value); }

/// A storage buffer of at least 16 bytes (an empty world still binds one) filled with `bytes`.
[[nodiscard]] Result<compute::Buffer> storage_with(gpu::VulkanContext& ctx, std::span<const std::byte> bytes);
/// `slot` becomes a storage buffer holding `bytes` (storage_with).
[[nodiscard]] Result<void> store(gpu::VulkanContext& ctx, std::optional<compute::Buffer>& slot, std::span<const std::byte> bytes);

/// A layer's pipeline: depth tested, the renderer's push constants (RenderPush), and
/// `storage_buffers` read by the vertex shader.
[[nodiscard]] Result<gpu::GraphicsPipeline> layer_pipeline(const LayerTarget& target, std::string_view vertex, std::string_view fragment,
                                                           std::uint32_t vertex_stride, std::uint32_t attributes,
                                                           std::uint32_t storage_buffers,
                                                           vk::PrimitiveTopology topology = vk::PrimitiveTopology::eTriangleList);
/// layer_pipeline() and a descriptor set of it, into `pipeline` and `set`.
[[nodiscard]] Result<void> layer_pipeline_with_set(const LayerTarget& target, std::string_view vertex, std::string_view fragment,
                                                   std::uint32_t vertex_stride, std::uint32_t attributes, std::uint32_t storage_buffers,
                                                   std::optional<gpu::GraphicsPipeline>& pipeline, std::optional<gpu::BufferSet>& set);

}  // namespace kodawari::render
