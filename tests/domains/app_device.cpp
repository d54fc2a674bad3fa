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

}  // namespace kodawari::testing_support
