#include "backends/backends.hpp"
#include "backends/device_backends.hpp"

namespace kodawari {

Result<std::shared_ptr<compute::Device>> backend_context(const BackendOptions& options) {
    if (options.context) return options.context;
    auto created = compute::Device::create(
        {.device = options.device, .validation = options.validation, .force_staging = options.force_staging});
    if (!created) return created.error();
    return std::shared_ptr<compute::Device>(std::move(created).value());
}

std::string_view backend_name(BackendKind kind) {
    switch (kind) {
        case BackendKind::CpuReference: return "cpu-reference";
        case BackendKind::Cpu: return "cpu";
        case BackendKind::Vulkan: return "vulkan";
    }
    return "cpu-reference";
}

Result<std::shared_ptr<gpu::VulkanContext>> open_shared_device(const BackendOptions& options) {
    BackendOptions own = options;
    own.context.reset();
    return backend_context(own);
}

std::uint64_t read_back_bytes(const gpu::VulkanContext& device) { return device.read_back_bytes(); }

std::uint32_t validation_messages(const gpu::VulkanContext& device) { return device.validation_messages(); }

Result<std::unique_ptr<BirdBackend>> make_bird_backend(BackendKind kind, const BackendOptions& options) {
    switch (kind) {
        case BackendKind::CpuReference: return make_cpu_bird_backend(true, 1);
        case BackendKind::Cpu: return make_cpu_bird_backend(false, options.threads);
        case BackendKind::Vulkan: return make_vulkan_bird_backend(options);
    }
    return make_error(Error::Kind::Internal, "unknown backend");
}

Result<std::unique_ptr<RodBackend>> make_rod_backend(BackendKind kind, const BackendOptions& options) {
    switch (kind) {
        case BackendKind::CpuReference: return make_cpu_rod_backend(true, 1);
        case BackendKind::Cpu: return make_cpu_rod_backend(false, options.threads);
        case BackendKind::Vulkan: return make_vulkan_rod_backend(options);
    }
    return make_error(Error::Kind::Internal, "unknown backend");
}

}  // namespace kodawari
