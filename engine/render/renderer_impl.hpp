#pragma once
// What the files of the renderer share (not public): renderer.cpp (the device, the pass,
// the pipelines, a frame's recording and read-back) and renderer_present.cpp (the
// swapchain and presenting into it): the renderer's state.

#include <algorithm>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "gpu/compute_vulkan.hpp"
#include "gpu/graphics.hpp"
#include "kodawari/render/renderer.hpp"
#include "render/draw_recorder.hpp"
#include "render/layer.hpp"

namespace kodawari::render {

// Presentation (RendererOptions::create_surface): the swapchain and its own command buffer
// and fence, because the frame's submission waits on and signals semaphores. At namespace
// scope, not nested in Impl: clang (< 16) does not see a nested struct's default member
// initializers while the enclosing class is incomplete, and std::optional::emplace() then
// finds no default constructor.
struct PresentTarget {
    vk::raii::SwapchainKHR swapchain{nullptr};
    std::vector<vk::Image> images;
    vk::Extent2D extent{};     // the swapchain's
    vk::Extent2D requested{};  // the window's framebuffer size it was made for
    bool stale = false;        // out of date or suboptimal: remade on the next present()
    vk::raii::Semaphore acquired{nullptr};
    // One per swapchain image: a present may still wait on an image's semaphore when
    // the next frame starts, so it is reused only when that image comes back.
    std::vector<vk::raii::Semaphore> finished;
    vk::raii::CommandPool pool{nullptr};
    vk::raii::CommandBuffer cmd{nullptr};
    vk::raii::Fence fence{nullptr};
};

struct Renderer::Impl {
    std::shared_ptr<gpu::VulkanContext> ctx;
    DrawRecorder draws;  // what domains drew through render::Draw

    // `list`, or a copy of it with what domains drew, sized for its camera.
    [[nodiscard]] const DrawList& with_draws(const DrawList& list, std::optional<DrawList>& merged) const {
        if (draws.empty()) return list;
        merged.emplace(list);
        draws.replay(*merged, std::clamp(static_cast<float>(list.height()) / 720.0f, 0.5f, 2.0f));
        return *merged;
    }

    std::uint32_t width = 0, height = 0;
    bool joints = false;  // RendererOptions::joints
    vk::SampleCountFlagBits samples = vk::SampleCountFlagBits::e1;
    // color: the image read back or blitted; multisampled: msaa_color is drawn into and
    // resolved into color at the end of the pass.
    std::optional<gpu::GpuImage> color, msaa_color, depth;
    vk::raii::RenderPass pass{nullptr};
    vk::raii::Framebuffer framebuffer{nullptr};
    std::optional<gpu::GraphicsPipeline> background, lines, triangles, shadows;
    std::optional<compute::Buffer> vertices, readback;
    // What domains draw from device buffers (render/layer.hpp), in drawing order.
    struct NamedLayer {
        int order = 0;
        std::string name;
        std::unique_ptr<Layer> layer;
    };
    std::vector<NamedLayer> layers;

    // Presentation, when the renderer has a surface (PresentTarget above).
    std::optional<PresentTarget> window;

    [[nodiscard]] Result<void> upload(const DrawList& list);
    void record_pass(const vk::raii::CommandBuffer& cmd, const DrawList& list) const;
    [[nodiscard]] Result<void> make_swapchain(std::uint32_t width, std::uint32_t height);
};

}  // namespace kodawari::render
