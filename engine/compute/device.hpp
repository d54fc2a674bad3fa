#pragma once
// The device of the compute layer (namespace kodawari::compute): what the domains' GPU code
// (engine/backends/vulkan_*.cpp, the render layers' kernels) is written against. Its one
// implementation is Vulkan, kept in engine/gpu/ (the instance, device selection, graphics
// for the renderer): gpu/ stays the Vulkan folder so that the renderer's graphics code,
// which is Vulkan by nature, keeps using it directly, while the compute vocabulary
// (Device, Buffer, Kernel, Queue, Recording, Submission) lives here.

#include <string_view>
#include <type_traits>
#include <utility>

#include "gpu/vulkan_context.hpp"

namespace kodawari::compute {

/// A device with one queue. Created by gpu::VulkanContext::create (device selection
/// separate from the rest, so that a device the application owns can later be adopted
/// instead); shared between backends and the renderer through std::shared_ptr.
using Device = gpu::VulkanContext;

/// The one place where exceptions from vulkan.hpp become Errors: runs `body` (which
/// returns a Result) and turns a vk::SystemError into an Error of kind Vulkan that keeps
/// the VkResult (Error::vk_result), naming `what` was being done.
template <typename F>
[[nodiscard]] auto guard(std::string_view what, F&& body) -> std::invoke_result_t<F&> {
    try {
        return body();
    } catch (const std::exception& e) {
        return gpu::vulkan_error(std::string(what), e);
    }
}

}  // namespace kodawari::compute
