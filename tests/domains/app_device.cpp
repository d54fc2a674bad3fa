// AppDevice (app_device.hpp) over testing_support::Application, with the loader's prototypes.
#include "domains/app_device.hpp"

#include "vulkan_app_support.hpp"

namespace kodawari::testing_support {

struct AppDevice::Impl {
    Application app;
};

AppDevice::AppDevice() : impl_(std::make_unique<Impl>()) {}
AppDevice::~AppDevice() = default;
bool AppDevice::ok() const { return impl_->app.ok(); }
VulkanDeviceHandles AppDevice::handles() const { return impl_->app.handles(); }
VkCommandBuffer AppDevice::begin(std::uint32_t k) { return impl_->app.begin(k); }
void AppDevice::submit(std::uint32_t k) { impl_->app.submit(k); }
void AppDevice::wait_all() { impl_->app.wait_all(); }
std::uint32_t AppDevice::messages() const { return testing_support::messages; }
void AppDevice::write_buffer(VkCommandBuffer cmd, VkBuffer buffer, VkDeviceSize offset, const void* data, VkDeviceSize bytes) {
    // After the compute shaders that read it before (the previous frame's step), then the
    // write; whoever reads it next makes the write visible to itself.
    const VkMemoryBarrier after_reads{VK_STRUCTURE_TYPE_MEMORY_BARRIER, nullptr, 0, 0};
    vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_PIPELINE_STAGE_TRANSFER_BIT, 0, 1, &after_reads, 0, nullptr,
                         0, nullptr);
    vkCmdUpdateBuffer(cmd, buffer, offset, bytes, data);
}

}  // namespace kodawari::testing_support
