#pragma once
// The device of the compute layer (namespace kodawari::compute): what the domains' GPU code
// (engine/backends/vulkan_*.cpp, the render layers' kernels) is written against. Its one
// implementation is Vulkan, kept in engine/gpu/ (the instance, device selection, graphics
// for the renderer): gpu/ stays the Vulkan folder so that the renderer's graphics code,
// which is Vulkan by nature, keeps using it directly, while the compute vocabulary
// (Device, Buffer, Kernel, Queue, Recording, Submission) lives here.

#include "gpu/vulkan_context.hpp"

namespace kodawari::compute {

/// A device with one queue. Created by gpu::VulkanContext::create (device selection
/// separate from the rest, so that a device the application owns can later be adopted
/// instead); shared between backends and the renderer through std::shared_ptr.
using Device = gpu::VulkanContext;

/// The boundary where exceptions from vulkan.hpp become Errors: gpu::guard itself, named
/// here so that the compute layer's code reads in its own vocabulary; one definition, so
/// that the compute path, device setup and the renderer map failures the same way.
using gpu::guard;

}  // namespace kodawari::compute
