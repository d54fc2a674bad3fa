// The renderer's presentation (RendererOptions::create_surface, Renderer::present): the
// swapchain, made and remade for the window's size, and a frame rendered and blitted into
// one of its images (renderer.cpp renders).

#include <algorithm>
#include <cassert>
#include <cstdint>
#include <optional>
#include <utility>

#include "render/renderer_impl.hpp"

namespace kodawari::render {
namespace {

// The window changed size under the swapchain: control flow (remake it on the next
// present()), not a failure, told apart by the VkResult that guard() keeps.
bool out_of_date(const Error& error) { return error.vk_result == static_cast<int>(vk::Result::eErrorOutOfDateKHR); }

}  // namespace

Result<void> Renderer::Impl::make_swapchain(std::uint32_t w, std::uint32_t h) {
    const gpu::VulkanContext& c = *ctx;
    const vk::raii::SurfaceKHR& surface = c.surface();
    if (!window) {
        window.emplace();
        window->acquired = c.device().createSemaphore({});
        window->pool = c.device().createCommandPool(
            {.flags = vk::CommandPoolCreateFlagBits::eResetCommandBuffer, .queueFamilyIndex = c.queue_family()});
        window->cmd = std::move(c.device().allocateCommandBuffers(
            {.commandPool = *window->pool, .level = vk::CommandBufferLevel::ePrimary, .commandBufferCount = 1})[0]);
        window->fence = c.device().createFence({});
    }
    c.device().waitIdle();  // the old swapchain's images are no longer in use
    const auto caps = c.physical_device().getSurfaceCapabilitiesKHR(*surface);
    if (!(caps.supportedUsageFlags & vk::ImageUsageFlagBits::eTransferDst)) {
        return make_error(Error::Kind::Unsupported, c.info().name + ": the window's images cannot be blitted to");
    }
    vk::Extent2D extent = caps.currentExtent;
    if (extent.width == UINT32_MAX) {
        extent = vk::Extent2D{.width = std::clamp(w, caps.minImageExtent.width, caps.maxImageExtent.width),
                              .height = std::clamp(h, caps.minImageExtent.height, caps.maxImageExtent.height)};
    }
    window->extent = extent;
    window->requested = vk::Extent2D{w, h};
    window->stale = false;
    window->images.clear();
    window->finished.clear();
    if (extent.width == 0 || extent.height == 0) return {};  // minimized: try again later
    // A UNORM format: the renderer's colours are sRGB values already (an _SRGB swapchain
    // would encode them a second time).
    const auto formats = c.physical_device().getSurfaceFormatsKHR(*surface);
    vk::SurfaceFormatKHR format = formats.front();
    for (const auto& f : formats) {
        if ((f.format == vk::Format::eB8G8R8A8Unorm || f.format == vk::Format::eR8G8B8A8Unorm) &&
            f.colorSpace == vk::ColorSpaceKHR::eSrgbNonlinear) {
            format = f;
            break;
        }
    }
    std::uint32_t image_count = caps.minImageCount + 1;
    if (caps.maxImageCount > 0) image_count = std::min(image_count, caps.maxImageCount);
    vk::raii::SwapchainKHR old = std::move(window->swapchain);
    window->swapchain = c.device().createSwapchainKHR({.surface = *surface,
                                                       .minImageCount = image_count,
                                                       .imageFormat = format.format,
                                                       .imageColorSpace = format.colorSpace,
                                                       .imageExtent = extent,
                                                       .imageArrayLayers = 1,
                                                       .imageUsage = vk::ImageUsageFlagBits::eTransferDst,
                                                       .imageSharingMode = vk::SharingMode::eExclusive,
                                                       .preTransform = caps.currentTransform,
                                                       .compositeAlpha = vk::CompositeAlphaFlagBitsKHR::eOpaque,
                                                       .presentMode = vk::PresentModeKHR::eFifo,
                                                       .clipped = VK_TRUE,
                                                       .oldSwapchain = *old});
    window->images = window->swapchain.getImages();
    for (std::size_t i = 0; i < window->images.size(); ++i) window->finished.push_back(c.device().createSemaphore({}));
    return {};
}

Result<bool> Renderer::present(const DrawList& list, std::uint32_t window_width, std::uint32_t window_height) {
    assert(list.width() == impl_->width && list.height() == impl_->height && "the draw list is for another size");
    Impl& r = *impl_;
    gpu::VulkanContext& c = *r.ctx;
    if (static_cast<VkSurfaceKHR>(*c.surface()) == VK_NULL_HANDLE) {
        return make_error(Error::Kind::Unsupported, "present() needs a renderer made with a window surface");
    }
    return gpu::guard("Vulkan presentation", [&]() -> Result<bool> {
        if (!r.window || r.window->stale || r.window->requested != vk::Extent2D{window_width, window_height}) {
            KW_TRY(r.make_swapchain(window_width, window_height));
        }
        if (r.window->images.empty()) return false;  // minimized
        PresentTarget& w = *r.window;
        // No image (a timeout) is not an error: the frame is skipped.
        auto acquired = gpu::guard("Vulkan swapchain image", [&]() -> Result<std::optional<std::uint32_t>> {
            const auto [result, i] = w.swapchain.acquireNextImage(UINT64_MAX, *w.acquired);
            if (result != vk::Result::eSuccess && result != vk::Result::eSuboptimalKHR) return std::optional<std::uint32_t>{};
            return std::optional<std::uint32_t>{i};
        });
        if (!acquired) {
            if (!out_of_date(acquired.error())) return acquired.error();
            w.stale = true;
            return false;
        }
        if (!acquired.value()) return false;
        const std::uint32_t index = *acquired.value();
        std::optional<DrawList> merged;
        const DrawList& frame = r.with_draws(list, merged);
        KW_TRY(r.upload(frame));
        w.cmd.reset();
        w.cmd.begin({.flags = vk::CommandBufferUsageFlagBits::eOneTimeSubmit});
        r.record_pass(w.cmd, frame);
        const vk::ImageSubresourceRange range{.aspectMask = vk::ImageAspectFlagBits::eColor, .levelCount = 1, .layerCount = 1};
        // The acquire semaphore is waited for at the transfer stage; the image's old
        // contents are not needed.
        const vk::ImageMemoryBarrier to_transfer{.srcAccessMask = {},
                                                 .dstAccessMask = vk::AccessFlagBits::eTransferWrite,
                                                 .oldLayout = vk::ImageLayout::eUndefined,
                                                 .newLayout = vk::ImageLayout::eTransferDstOptimal,
                                                 .srcQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED,
                                                 .dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED,
                                                 .image = w.images[index],
                                                 .subresourceRange = range};
        w.cmd.pipelineBarrier(vk::PipelineStageFlagBits::eTransfer, vk::PipelineStageFlagBits::eTransfer, {}, {}, {}, to_transfer);
        const vk::ImageSubresourceLayers layers{.aspectMask = vk::ImageAspectFlagBits::eColor, .layerCount = 1};
        const vk::ImageBlit blit{.srcSubresource = layers,
                                 .srcOffsets = std::array<vk::Offset3D, 2>{vk::Offset3D{0, 0, 0},
                                                                           vk::Offset3D{static_cast<std::int32_t>(r.width),
                                                                                        static_cast<std::int32_t>(r.height), 1}},
                                 .dstSubresource = layers,
                                 .dstOffsets = std::array<vk::Offset3D, 2>{
                                     vk::Offset3D{0, 0, 0}, vk::Offset3D{static_cast<std::int32_t>(w.extent.width),
                                                                         static_cast<std::int32_t>(w.extent.height), 1}}};
        w.cmd.blitImage(r.color->handle(), vk::ImageLayout::eTransferSrcOptimal, w.images[index],
                        vk::ImageLayout::eTransferDstOptimal, blit, vk::Filter::eLinear);
        const vk::ImageMemoryBarrier to_present{.srcAccessMask = vk::AccessFlagBits::eTransferWrite,
                                                .dstAccessMask = {},
                                                .oldLayout = vk::ImageLayout::eTransferDstOptimal,
                                                .newLayout = vk::ImageLayout::ePresentSrcKHR,
                                                .srcQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED,
                                                .dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED,
                                                .image = w.images[index],
                                                .subresourceRange = range};
        w.cmd.pipelineBarrier(vk::PipelineStageFlagBits::eTransfer, vk::PipelineStageFlagBits::eBottomOfPipe, {}, {}, {}, to_present);
        w.cmd.end();
        c.device().resetFences(*w.fence);
        const vk::PipelineStageFlags wait_stage = vk::PipelineStageFlagBits::eTransfer;
        const vk::CommandBuffer cmd = *w.cmd;
        const vk::Semaphore wait = *w.acquired, signal = *w.finished[index];
        c.queue().submit(vk::SubmitInfo{.waitSemaphoreCount = 1,
                                        .pWaitSemaphores = &wait,
                                        .pWaitDstStageMask = &wait_stage,
                                        .commandBufferCount = 1,
                                        .pCommandBuffers = &cmd,
                                        .signalSemaphoreCount = 1,
                                        .pSignalSemaphores = &signal},
                         *w.fence);
        // One frame at a time: the vertex buffer and the offscreen image are reused.
        constexpr std::uint64_t kTimeoutNs = 600ull * 1000 * 1000 * 1000;
        if (c.device().waitForFences(*w.fence, VK_TRUE, kTimeoutNs) != vk::Result::eSuccess) {
            // As compute::Submission::wait does: the code tells a hang from a failure.
            Error error = make_error(Error::Kind::Vulkan, "the GPU did not finish a frame within 600 s");
            error.vk_result = static_cast<int>(vk::Result::eTimeout);
            return error;
        }
        const vk::SwapchainKHR swapchain = *w.swapchain;
        auto presented = gpu::guard("Vulkan present", [&]() -> Result<void> {
            const vk::Result result = c.queue().presentKHR(
                {.waitSemaphoreCount = 1, .pWaitSemaphores = &signal, .swapchainCount = 1, .pSwapchains = &swapchain, .pImageIndices = &index});
            if (result == vk::Result::eSuboptimalKHR) w.stale = true;
            return {};
        });
        if (!presented) {
            if (!out_of_date(presented.error())) return presented.error();
            w.stale = true;  // shown or not, the next present() remakes the swapchain
        }
        return true;
    });
}

}  // namespace kodawari::render
