// The factories of every backend kind (kodawari/vulkan/backend_factory.hpp says why they live in
// the vulkan target): the CPU kinds come from kodawari::sim.
#include "kodawari/vulkan/backend_factory.hpp"

#include "vulkan_backends/device_backends.hpp"
#include "gpu/vulkan_context.hpp"

namespace kodawari {

Result<std::shared_ptr<compute::Device>> backend_context(const BackendOptions& options) {
    if (options.context) return options.context;
    auto created = gpu::VulkanContext::create({.device = options.device,
                                               .validation = options.validation,
                                               .force_staging = options.force_staging,
                                               .capture_statistics = options.kernel_statistics});
    if (!created) return created.error();
    return std::shared_ptr<compute::Device>(std::move(created).value());
}

Result<std::shared_ptr<compute::Device>> open_shared_device(const BackendOptions& options) {
    BackendOptions own = options;
    own.context.reset();
    return backend_context(own);
}

Result<std::shared_ptr<compute::Device>> open_auto_device(const BackendOptions& options, std::string& cpu_reason) {
    cpu_reason.clear();
    if (options.context) return options.context;
    auto device = open_shared_device(options);
    if (!options.device.empty()) return device;  // named: obeyed, or the error
    if (!device) {
        cpu_reason = device.error().message;
        return std::shared_ptr<compute::Device>{};
    }
    cpu_reason = auto_passes_over(device.value()->info());
    if (!cpu_reason.empty()) return std::shared_ptr<compute::Device>{};
    return device;
}

Result<std::unique_ptr<BirdBackend>> make_bird_backend(BackendKind kind, const BackendOptions& options) {
    if (kind == BackendKind::Vulkan) return make_vulkan_bird_backend(options);
    return make_cpu_bird_backend(kind, options);
}

Result<std::unique_ptr<RodBackend>> make_rod_backend(BackendKind kind, const BackendOptions& options) {
    if (kind == BackendKind::Vulkan) return make_vulkan_rod_backend(options);
    return make_cpu_rod_backend(kind, options);
}

Result<std::unique_ptr<PoseBackend>> make_pose_backend(BackendKind kind, const BackendOptions& options) {
    if (kind == BackendKind::Vulkan) return make_vulkan_pose_backend(options);
    return make_cpu_pose_backend(kind, options);
}

}  // namespace kodawari
