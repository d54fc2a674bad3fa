#pragma once
// An application's own Vulkan device and command buffers (testing_support::Application of
// tests/vulkan_app_support.hpp) behind a narrow interface, compiled in a file of its own:
// the domain contract test compiles the engine's compute layer, whose vulkan.hpp settings
// (VK_NO_PROTOTYPES) hide the loader's prototypes the application calls.
#include <cstdint>
#include <memory>

#include <vulkan/vulkan_core.h>

#include "kodawari/vulkan/vulkan_embed.hpp"

namespace kodawari::testing_support {

class AppDevice {
public:
    AppDevice();
    ~AppDevice();
    AppDevice(const AppDevice&) = delete;
    AppDevice& operator=(const AppDevice&) = delete;

    [[nodiscard]] bool ok() const;
    [[nodiscard]] VulkanDeviceHandles handles() const;
    /// Frame k's command buffer, recording, once the GPU finished frame k - frames in flight.
    [[nodiscard]] VkCommandBuffer begin(std::uint32_t k);
    void submit(std::uint32_t k);
    void wait_all();
    /// Records into `cmd` what an application's kernel writing `bytes` of `buffer` at
    /// `offset` would: a barrier after earlier compute-shader reads, then the write
    /// (vkCmdUpdateBuffer: at most 65 536 bytes).
    void write_buffer(VkCommandBuffer cmd, VkBuffer buffer, VkDeviceSize offset, const void* data, VkDeviceSize bytes);
    /// Validation messages the application's messenger saw.
    [[nodiscard]] std::uint32_t messages() const;

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace kodawari::testing_support
