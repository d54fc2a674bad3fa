#include "gpu/vulkan_context.hpp"

#include "gpu/compute_vulkan.hpp"

#include <algorithm>
#include <cassert>
#include <cctype>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <dlfcn.h>
#include <optional>

VULKAN_HPP_DEFAULT_DISPATCH_LOADER_DYNAMIC_STORAGE

namespace kodawari::gpu {
namespace {

std::string version_text(std::uint32_t v) {
    return std::to_string(VK_API_VERSION_MAJOR(v)) + "." + std::to_string(VK_API_VERSION_MINOR(v)) + "." +
           std::to_string(VK_API_VERSION_PATCH(v));
}

const char* type_name(vk::PhysicalDeviceType type) {
    switch (type) {
        case vk::PhysicalDeviceType::eDiscreteGpu: return "discrete";
        case vk::PhysicalDeviceType::eIntegratedGpu: return "integrated";
        case vk::PhysicalDeviceType::eVirtualGpu: return "virtual";
        case vk::PhysicalDeviceType::eCpu: return "cpu";
        default: return "other";
    }
}

std::optional<std::uint32_t> compute_family(const vk::raii::PhysicalDevice& device, bool graphics = false) {
    const auto families = device.getQueueFamilyProperties();
    if (graphics) {
        const auto both = vk::QueueFlagBits::eGraphics | vk::QueueFlagBits::eCompute;
        for (std::uint32_t i = 0; i < families.size(); ++i) {
            if ((families[i].queueFlags & both) == both) return i;
        }
        return std::nullopt;
    }
    // A compute-only family first (async compute on GPUs), else any with compute.
    for (std::uint32_t i = 0; i < families.size(); ++i) {
        const auto flags = families[i].queueFlags;
        if ((flags & vk::QueueFlagBits::eCompute) && !(flags & vk::QueueFlagBits::eGraphics)) return i;
    }
    for (std::uint32_t i = 0; i < families.size(); ++i) {
        if (families[i].queueFlags & vk::QueueFlagBits::eCompute) return i;
    }
    return std::nullopt;
}

GpuDeviceInfo describe(const vk::raii::PhysicalDevice& device, std::uint32_t index) {
    const auto chain = device.getProperties2<vk::PhysicalDeviceProperties2, vk::PhysicalDeviceSubgroupProperties,
                                             vk::PhysicalDeviceDriverProperties>();
    const auto& props = chain.get<vk::PhysicalDeviceProperties2>().properties;
    const auto& driver = chain.get<vk::PhysicalDeviceDriverProperties>();
    GpuDeviceInfo info;
    info.index = index;
    info.name = props.deviceName.data();
    info.type = type_name(props.deviceType);
    info.driver = std::string(driver.driverName.data()) + " " + driver.driverInfo.data();
    info.api_version = version_text(props.apiVersion);
    const auto family = compute_family(device);
    info.has_compute_queue = family.has_value();
    // The engine's own needs, whatever the context is for: its kernels are SPIR-V for
    // Vulkan 1.1 (cmake/KodawariShaders.cmake's --target-env) and run on a compute queue.
    if (props.apiVersion < VK_API_VERSION_1_1) {
        info.rejected = "Vulkan " + std::to_string(VK_API_VERSION_MAJOR(props.apiVersion)) + "." +
                        std::to_string(VK_API_VERSION_MINOR(props.apiVersion)) + " < 1.1 needed";
    } else if (!family) {
        info.rejected = "no queue family with compute";
    }
    if (family) {
        info.timestamps = props.limits.timestampPeriod > 0.0f &&
                          device.getQueueFamilyProperties()[*family].timestampValidBits > 0;
    }
    info.subgroup_size = chain.get<vk::PhysicalDeviceSubgroupProperties>().subgroupSize;
    info.max_workgroup_invocations = props.limits.maxComputeWorkGroupInvocations;
    info.max_workgroup_size_x = props.limits.maxComputeWorkGroupSize[0];
    info.max_workgroup_count = {props.limits.maxComputeWorkGroupCount[0], props.limits.maxComputeWorkGroupCount[1],
                                props.limits.maxComputeWorkGroupCount[2]};
    info.max_storage_buffer_range = props.limits.maxStorageBufferRange;
    info.max_shared_memory = props.limits.maxComputeSharedMemorySize;
    info.max_push_constants = props.limits.maxPushConstantsSize;
    const auto memory = device.getMemoryProperties();
    for (std::uint32_t h = 0; h < memory.memoryHeapCount; ++h) {
        if (memory.memoryHeaps[h].flags & vk::MemoryHeapFlagBits::eDeviceLocal) info.device_local_bytes += memory.memoryHeaps[h].size;
    }
    return info;
}

std::string lower(std::string text) {
    std::transform(text.begin(), text.end(), text.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    return text;
}

// "name: reason" for each device passed over (vk-bootstrap keeps these too): for
// Error::rejected_devices and the messages of a failed selection.
std::vector<std::string> rejections(const GpuInventory& inventory) {
    std::vector<std::string> out;
    for (const GpuDeviceInfo& d : inventory.devices) {
        if (!d.rejected.empty()) out.push_back(d.name + ": " + d.rejected);
    }
    return out;
}

// Why no device was chosen, followed by each device's reason, so that one line of a
// message says what to change (a driver, the request).
std::string none_because(const GpuInventory& inventory, const std::string& why) {
    std::string text = why;
    const auto reasons = rejections(inventory);
    for (std::size_t i = 0; i < reasons.size(); ++i) text += (i == 0 ? " (passed over: " : "; ") + reasons[i];
    if (!reasons.empty()) text += ")";
    return text;
}

// Picks a device among those not rejected (GpuDeviceInfo::rejected): by index or name
// substring when asked, else the best type. A request marks each device it passes over
// with why, so that a failed selection names every device and its reason.
void choose(GpuInventory& inventory, const std::string& request) {
    auto& devices = inventory.devices;
    if (!request.empty()) {
        const bool numeric = std::all_of(request.begin(), request.end(), [](unsigned char c) { return std::isdigit(c); });
        for (std::size_t i = 0; i < devices.size(); ++i) {
            const bool match = numeric ? std::to_string(devices[i].index) == request
                                       : lower(devices[i].name).find(lower(request)) != std::string::npos;
            if (!devices[i].rejected.empty()) continue;  // its own reason says more than the request
            if (!match) {
                devices[i].rejected = numeric ? "is device " + std::to_string(devices[i].index) + ", not " + request
                                              : "does not match \"" + request + "\"";
            } else if (inventory.chosen < 0) {
                inventory.chosen = static_cast<int>(i);
                inventory.reason = "asked for \"" + request + "\"";
            }
        }
        if (inventory.chosen < 0) {
            inventory.reason = none_because(inventory, "no usable Vulkan device matches \"" + request + "\"");
        }
        return;
    }
    static constexpr const char* kOrder[] = {"discrete", "integrated", "virtual", "cpu", "other"};
    for (const char* type : kOrder) {
        for (std::size_t i = 0; i < devices.size(); ++i) {
            if (devices[i].type == type && devices[i].rejected.empty()) {
                inventory.chosen = static_cast<int>(i);
                inventory.reason = std::string("the first ") + type +
                                   " device (preference: discrete > integrated > virtual > cpu)";
                return;
            }
        }
    }
    inventory.reason = none_because(inventory, "no Vulkan device is usable");
}

VKAPI_ATTR VkBool32 VKAPI_CALL on_validation_message(VkDebugUtilsMessageSeverityFlagBitsEXT severity,
                                                     VkDebugUtilsMessageTypeFlagsEXT,
                                                     const VkDebugUtilsMessengerCallbackDataEXT* data, void* user) {
    if (severity >= VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT) {
        static_cast<std::atomic<std::uint32_t>*>(user)->fetch_add(1);
        std::fprintf(stderr, "[vulkan validation] %s\n", data->pMessage != nullptr ? data->pMessage : "(no message)");
    }
    return VK_FALSE;
}

Result<std::unique_ptr<vk::raii::Context>> open_loader() {
    // Opened once and kept for the process (never closed: instances of several contexts,
    // and the validation layer, may live until exit).
    static void* const library = [] {
        void* lib = ::dlopen("libvulkan.so.1", RTLD_NOW | RTLD_LOCAL);
        return lib != nullptr ? lib : ::dlopen("libvulkan.so", RTLD_NOW | RTLD_LOCAL);
    }();
    if (library == nullptr) {
        // The machine's setup (the command line falls back to the CPU), not a Vulkan call
        // that failed: no VkResult.
        return make_error(Error::Kind::Unsupported,
                          "no Vulkan loader (libvulkan.so.1; Debian package libvulkan1, which scripts/setup installs)");
    }
    auto* const entry = reinterpret_cast<PFN_vkGetInstanceProcAddr>(::dlsym(library, "vkGetInstanceProcAddr"));
    if (entry == nullptr) return make_error(Error::Kind::Unsupported, "the Vulkan loader has no vkGetInstanceProcAddr");
    return guard("Vulkan loader", [&]() -> Result<std::unique_ptr<vk::raii::Context>> {
        return std::make_unique<vk::raii::Context>(entry);
    });
}

// The queue family this context uses on `device`: one that draws (and, with a surface,
// presents to it) when asked, else compute_family's choice.
std::optional<std::uint32_t> usable_family(const vk::raii::PhysicalDevice& device, bool graphics,
                                          const vk::raii::SurfaceKHR& surface) {
    if (static_cast<VkSurfaceKHR>(*surface) == VK_NULL_HANDLE) return compute_family(device, graphics);
    // One queue does everything, so it must also present to the window.
    const auto families = device.getQueueFamilyProperties();
    const auto both = vk::QueueFlagBits::eGraphics | vk::QueueFlagBits::eCompute;
    for (std::uint32_t i = 0; i < families.size(); ++i) {
        if ((families[i].queueFlags & both) == both && device.getSurfaceSupportKHR(i, *surface)) return i;
    }
    return std::nullopt;
}

vk::raii::Instance make_instance(const vk::raii::Context& context, bool validation,
                                 const std::vector<std::string>& extra_extensions = {}) {
    const std::uint32_t loader_version = context.enumerateInstanceVersion();
    const vk::ApplicationInfo app{.pApplicationName = "kodawari",
                                  .applicationVersion = 1,
                                  .pEngineName = "kodawari",
                                  .engineVersion = 1,
                                  .apiVersion = std::min(loader_version, VK_API_VERSION_1_3)};
    std::vector<const char*> layers, extensions;
    static constexpr vk::ValidationFeatureEnableEXT kFeatures[] = {vk::ValidationFeatureEnableEXT::eSynchronizationValidation};
    vk::ValidationFeaturesEXT features{.enabledValidationFeatureCount = 1, .pEnabledValidationFeatures = kFeatures};
    if (validation) {
        layers.push_back("VK_LAYER_KHRONOS_validation");
        extensions.push_back(VK_EXT_DEBUG_UTILS_EXTENSION_NAME);
    }
    for (const std::string& e : extra_extensions) extensions.push_back(e.c_str());
    const vk::InstanceCreateInfo info{.pNext = validation ? &features : nullptr,
                                      .pApplicationInfo = &app,
                                      .enabledLayerCount = static_cast<std::uint32_t>(layers.size()),
                                      .ppEnabledLayerNames = layers.data(),
                                      .enabledExtensionCount = static_cast<std::uint32_t>(extensions.size()),
                                      .ppEnabledExtensionNames = extensions.data()};
    return vk::raii::Instance(context, info);
}

bool has_validation_layer(const vk::raii::Context& context) {
    for (const auto& layer : context.enumerateInstanceLayerProperties()) {
        if (std::strcmp(layer.layerName.data(), "VK_LAYER_KHRONOS_validation") == 0) return true;
    }
    return false;
}

}  // namespace

Error vulkan_error(const std::string& what, const std::exception& e) {
    // The loader answers "incompatible driver" when it found no usable driver at all.
    if (dynamic_cast<const vk::IncompatibleDriverError*>(&e) != nullptr) {
        Error none = make_error(Error::Kind::Unsupported,
                                "no Vulkan driver found (install Mesa's lavapipe, Debian package mesa-vulkan-drivers, or a GPU driver)");
        none.vk_result = VK_ERROR_INCOMPATIBLE_DRIVER;
        return none;
    }
    Error error = make_error(Error::Kind::Vulkan, what + ": " + e.what());
    if (const auto* system = dynamic_cast<const vk::SystemError*>(&e); system != nullptr) {
        error.vk_result = system->code().value();  // vk::Result's error category: the VkResult itself
    }
    return error;
}

}  // namespace kodawari::gpu

namespace kodawari {

std::string auto_passes_over(const GpuDeviceInfo& device) {
    if (device.type != "cpu") return "";
    // Measured on this project's 2-core machine (docs/performance.md, issue 12): chains
    // 22x the reference on the cpu backend against 8.6x on lavapipe, birds 37x against 10x.
    return device.name + " is a CPU, not a GPU (Vulkan device type cpu): the cpu backend runs the same work several "
                         "times faster there; --backend vulkan, or naming the device, runs on it anyway";
}

void choose_gpu(GpuInventory& inventory, const std::string& request) {
    inventory.chosen = -1;
    inventory.reason.clear();
    gpu::choose(inventory, request);
}

bool vulkan_validation_available() {
    auto context = gpu::open_loader();
    if (!context) return false;
    auto found = gpu::guard("Vulkan layers", [&]() -> Result<bool> { return gpu::has_validation_layer(*context.value()); });
    return found && found.value();
}

Result<GpuInventory> list_gpus(const std::string& request) {
    auto context = gpu::open_loader();
    if (!context) return context.error();
    return gpu::guard("Vulkan instance", [&]() -> Result<GpuInventory> {
        const vk::raii::Instance instance = gpu::make_instance(*context.value(), false);
        GpuInventory inventory;
        const vk::raii::PhysicalDevices devices(instance);
        for (std::uint32_t i = 0; i < devices.size(); ++i) inventory.devices.push_back(gpu::describe(devices[i], i));
        if (inventory.devices.empty()) {
            inventory.reason = "the Vulkan loader found no device (is a driver such as Mesa's lavapipe installed?)";
        } else {
            choose_gpu(inventory, request);
        }
        return inventory;
    });
}

}  // namespace kodawari

namespace kodawari::gpu {

VulkanContext::~VulkanContext() {
    if (!adopted_) {
        if (static_cast<VkDevice>(*device_) != VK_NULL_HANDLE) device_.waitIdle();
        return;
    }
    // The application's device and instance: its own submissions are its to wait for
    // (docs/embedding.md: destroy the backends once the GPU finished their work); ours
    // were waited for. Our objects go first, while the device's dispatcher exists, then
    // the handles are let go of without being destroyed.
    timestamps_ = nullptr;
    free_slots_.clear();
    pool_ = nullptr;
    queue_ = nullptr;
    (void)device_.release();
    physical_ = nullptr;
    (void)instance_.release();
}

Result<std::unique_ptr<VulkanContext>> VulkanContext::create(const ContextOptions& options) {
    std::unique_ptr<VulkanContext> ctx(new VulkanContext());
    auto loader = open_loader();
    if (!loader) return loader.error();
    ctx->context_ = std::move(loader).value();
    ctx->validation_ = options.validation;
    KW_TRY(guard("Vulkan instance", [&]() -> Result<void> {
        if (ctx->validation_ && !has_validation_layer(*ctx->context_)) {
            return make_error(Error::Kind::Unsupported,
                              "validation was asked for but VK_LAYER_KHRONOS_validation is not installed "
                              "(Debian package vulkan-validationlayers; scripts/setup installs it)");
        }
        if (ctx->validation_) {
            // The layer keeps allocations until the process ends; pinned in memory, its
            // frames stay symbolized, so LeakSanitizer can tell them from ours
            // (tests/lsan.supp).
            (void)::dlopen("libVkLayer_khronos_validation.so", RTLD_NOW | RTLD_NODELETE);
        }
        ctx->instance_ = make_instance(*ctx->context_, ctx->validation_, options.instance_extensions);
        if (ctx->validation_) {
            using Severity = vk::DebugUtilsMessageSeverityFlagBitsEXT;
            using Type = vk::DebugUtilsMessageTypeFlagBitsEXT;
            ctx->messenger_ = ctx->instance_.createDebugUtilsMessengerEXT(
                {.messageSeverity = Severity::eWarning | Severity::eError,
                 .messageType = Type::eGeneral | Type::eValidation | Type::ePerformance,
                 .pfnUserCallback = &on_validation_message,
                 .pUserData = ctx->messages_.get()});
        }

        if (options.create_surface) {
            auto surface = options.create_surface(*ctx->instance_);
            if (!surface) return surface.error();
            ctx->surface_ = vk::raii::SurfaceKHR(ctx->instance_, surface.value());
        }
        return {};
    }));

    KW_TRY(guard("Vulkan device setup", [&]() -> Result<void> {
        GpuInventory inventory;
        vk::raii::PhysicalDevices devices(ctx->instance_);
        for (std::uint32_t i = 0; i < devices.size(); ++i) inventory.devices.push_back(describe(devices[i], i));
        if (inventory.devices.empty()) {
            return make_error(Error::Kind::Unsupported,
                              "no Vulkan device: the loader found no driver (install Mesa's lavapipe: mesa-vulkan-drivers)");
        }
        const bool presents = static_cast<VkSurfaceKHR>(*ctx->surface_) != VK_NULL_HANDLE;
        const bool graphics = options.graphics || presents;
        // This context's needs beyond the engine's own (describe()): a queue that draws
        // and presents, so that a device that cannot is passed over, not chosen and failed.
        for (GpuDeviceInfo& d : inventory.devices) {
            if (d.rejected.empty() && graphics && !usable_family(devices[d.index], graphics, ctx->surface_)) {
                d.rejected = presents ? "no queue family that does graphics and compute and presents to the window"
                                      : "no queue family that does graphics and compute";
            }
        }
        choose(inventory, options.device);
        if (inventory.chosen < 0) {
            // No Vulkan call failed (vk_result stays 0): every device was passed over. A
            // device the caller named that is not there is the caller's mistake (bad
            // input: the command line's exit 2), not a missing capability.
            Error none = make_error(options.device.empty() ? Error::Kind::Unsupported : Error::Kind::InvalidInput, inventory.reason);
            none.rejected_devices = rejections(inventory);
            return none;
        }
        ctx->info_ = inventory.devices[static_cast<std::size_t>(inventory.chosen)];
        ctx->physical_ = std::move(devices[ctx->info_.index]);
        const std::optional<std::uint32_t> family = usable_family(ctx->physical_, graphics, ctx->surface_);
        assert(family && "choose() passes over devices without the queue family");
        ctx->queue_family_ = *family;

        const float priority = 1.0f;
        const vk::DeviceQueueCreateInfo queue_info{.queueFamilyIndex = ctx->queue_family_, .queueCount = 1, .pQueuePriorities = &priority};
        std::vector<const char*> extensions;
        if (presents) extensions.push_back(VK_KHR_SWAPCHAIN_EXTENSION_NAME);
        // Kernel statistics (ContextOptions::capture_statistics): the extension and its one
        // feature, where the driver offers both; otherwise the note says which is missing.
        vk::PhysicalDevicePipelineExecutablePropertiesFeaturesKHR executable_info{.pipelineExecutableInfo = VK_TRUE};
        if (options.capture_statistics) {
            const char* name = VK_KHR_PIPELINE_EXECUTABLE_PROPERTIES_EXTENSION_NAME;
            bool offered = false;
            for (const vk::ExtensionProperties& e : ctx->physical_.enumerateDeviceExtensionProperties()) {
                offered = offered || std::string_view(e.extensionName) == name;
            }
            if (!offered) {
                ctx->statistics_note_ = "kernel statistics: " + ctx->info_.name + "'s driver does not offer " + name;
            } else if (!ctx->physical_
                            .getFeatures2<vk::PhysicalDeviceFeatures2, vk::PhysicalDevicePipelineExecutablePropertiesFeaturesKHR>()
                            .get<vk::PhysicalDevicePipelineExecutablePropertiesFeaturesKHR>()
                            .pipelineExecutableInfo) {
                ctx->statistics_note_ = "kernel statistics: " + ctx->info_.name + " offers " + name + " without pipelineExecutableInfo";
            } else {
                extensions.push_back(name);
                ctx->captures_statistics_ = true;
            }
        }
        ctx->device_ = ctx->physical_.createDevice({.pNext = ctx->captures_statistics_ ? &executable_info : nullptr,
                                                    .queueCreateInfoCount = 1,
                                                    .pQueueCreateInfos = &queue_info,
                                                    .enabledExtensionCount = static_cast<std::uint32_t>(extensions.size()),
                                                    .ppEnabledExtensionNames = extensions.empty() ? nullptr : extensions.data()});
        ctx->finish_setup(options.force_staging);
        return {};
    }));
    return ctx;
}

void VulkanContext::add_statistics(compute::KernelStatistics statistics) const {
    const std::lock_guard lock(statistics_mutex_);
    statistics_.push_back(std::move(statistics));
}

Result<std::vector<compute::KernelStatistics>> VulkanContext::kernel_statistics() const {
    if (!captures_statistics_) return make_error(Error::Kind::Unsupported, statistics_note_);
    const std::lock_guard lock(statistics_mutex_);
    return statistics_;
}

void VulkanContext::finish_setup(bool force_staging, std::uint32_t queue_index) {
    queue_ = device_.getQueue(queue_family_, queue_index);
    pool_ = device_.createCommandPool(
        {.flags = vk::CommandPoolCreateFlagBits::eResetCommandBuffer, .queueFamilyIndex = queue_family_}, allocator_);
    const auto families = physical_.getQueueFamilyProperties();
    graphics_queue_ = static_cast<bool>(families[queue_family_].queueFlags & vk::QueueFlagBits::eGraphics);
    const auto props = physical_.getProperties();
    memory_ = physical_.getMemoryProperties();
    if (info_.timestamps) {
        timestamp_period_ns_ = props.limits.timestampPeriod;
        const std::uint32_t bits = families[queue_family_].timestampValidBits;
        timestamp_mask_ = bits >= 64 ? ~0ull : ((1ull << bits) - 1);
        timestamps_ = device_.createQueryPool({.queryType = vk::QueryType::eTimestamp, .queryCount = 2}, allocator_);
    }
    // Unified memory: the device shares the host's RAM and exposes it as
    // device-local + host-visible + coherent, so mapping beats staging copies.
    // force_staging takes the discrete-GPU path anyway (tests use it).
    const bool shares_ram = props.deviceType == vk::PhysicalDeviceType::eIntegratedGpu ||
                            props.deviceType == vk::PhysicalDeviceType::eCpu;
    const auto unified_flags = vk::MemoryPropertyFlagBits::eDeviceLocal | vk::MemoryPropertyFlagBits::eHostVisible |
                               vk::MemoryPropertyFlagBits::eHostCoherent;
    bool has_unified_type = false;
    for (std::uint32_t i = 0; i < memory_.memoryTypeCount; ++i) {
        if ((memory_.memoryTypes[i].propertyFlags & unified_flags) == unified_flags) has_unified_type = true;
    }
    unified_ = shares_ram && has_unified_type && !force_staging;
}

Result<std::unique_ptr<VulkanContext>> VulkanContext::adopt(const AdoptOptions& options) {
    // Every check before the first call through the application's handles: a bad handle
    // is an error here, not a crash in the driver.
    if (options.instance == VK_NULL_HANDLE) return make_error(Error::Kind::InvalidInput, "VulkanDeviceHandles::instance is null");
    if (options.physical_device == VK_NULL_HANDLE) {
        return make_error(Error::Kind::InvalidInput, "VulkanDeviceHandles::physical_device is null");
    }
    if (options.device == VK_NULL_HANDLE) return make_error(Error::Kind::InvalidInput, "VulkanDeviceHandles::device is null");
    if (options.get_instance_proc_addr == nullptr) {
        return make_error(Error::Kind::InvalidInput,
                          "VulkanDeviceHandles::get_instance_proc_addr is null (pass the application's vkGetInstanceProcAddr)");
    }
    if (options.api_version < VK_API_VERSION_1_1) {
        return make_error(Error::Kind::InvalidInput, "VulkanDeviceHandles::api_version is " + version_text(options.api_version) +
                                                         "; the kernels need an instance created for Vulkan 1.1 or later");
    }
    if (options.frames_in_flight < 1 || options.frames_in_flight > 16) {
        return make_error(Error::Kind::InvalidInput, "VulkanDeviceHandles::frames_in_flight is " +
                                                         std::to_string(options.frames_in_flight) + "; expected 1 to 16");
    }
    std::unique_ptr<VulkanContext> ctx(new VulkanContext());
    ctx->adopted_ = true;
    ctx->frames_in_flight_ = options.frames_in_flight;
    ctx->allocator_ = reinterpret_cast<const vk::AllocationCallbacks*>(options.allocator);
    KW_TRY(guard("the application's Vulkan device", [&]() -> Result<void> {
        ctx->context_ = std::make_unique<vk::raii::Context>(options.get_instance_proc_addr);
        ctx->instance_ = vk::raii::Instance(*ctx->context_, options.instance, ctx->allocator_);
        ctx->physical_ = vk::raii::PhysicalDevice(ctx->instance_, options.physical_device);
        // The index among the instance's devices, for messages and `kodawari info`.
        std::uint32_t index = 0;
        const vk::raii::PhysicalDevices devices(ctx->instance_);
        for (std::uint32_t i = 0; i < devices.size(); ++i) {
            if (static_cast<VkPhysicalDevice>(*devices[i]) == options.physical_device) index = i;
        }
        ctx->info_ = describe(ctx->physical_, index);
        if (!ctx->info_.rejected.empty()) {
            return make_error(Error::Kind::Unsupported, ctx->info_.name + " cannot run the kernels: " + ctx->info_.rejected);
        }
        const auto families = ctx->physical_.getQueueFamilyProperties();
        if (options.queue_family >= families.size()) {
            return make_error(Error::Kind::InvalidInput, "VulkanDeviceHandles::queue_family is " + std::to_string(options.queue_family) +
                                                             "; " + ctx->info_.name + " has " + std::to_string(families.size()) +
                                                             " queue families");
        }
        if (!(families[options.queue_family].queueFlags & vk::QueueFlagBits::eCompute)) {
            return make_error(Error::Kind::InvalidInput, "VulkanDeviceHandles::queue_family " + std::to_string(options.queue_family) +
                                                             " has no compute; the module records compute dispatches");
        }
        if (options.queue_index >= families[options.queue_family].queueCount) {
            return make_error(Error::Kind::InvalidInput, "VulkanDeviceHandles::queue_index is " + std::to_string(options.queue_index) +
                                                             "; the family has " +
                                                             std::to_string(families[options.queue_family].queueCount) + " queues");
        }
        ctx->info_.timestamps = ctx->info_.timestamps && families[options.queue_family].timestampValidBits > 0;
        ctx->queue_family_ = options.queue_family;
        ctx->device_ = vk::raii::Device(ctx->physical_, options.device, ctx->allocator_);
        ctx->finish_setup(false, options.queue_index);
        return {};
    }));
    return ctx;
}

Result<CommandSlot> VulkanContext::acquire_slot() {
    if (!free_slots_.empty()) {
        CommandSlot slot = std::move(free_slots_.back());
        free_slots_.pop_back();
        return slot;
    }
    return guard("Vulkan command buffer", [&]() -> Result<CommandSlot> {
        CommandSlot slot;
        slot.cmd = std::move(device_.allocateCommandBuffers(
            {.commandPool = *pool_, .level = vk::CommandBufferLevel::ePrimary, .commandBufferCount = 1})[0]);
        slot.fence = device_.createFence({}, allocator_);
        return slot;
    });
}

void VulkanContext::release_slot(CommandSlot slot) {
    if (static_cast<VkCommandBuffer>(*slot.cmd) != VK_NULL_HANDLE) free_slots_.push_back(std::move(slot));
}

double VulkanContext::timestamp_ms() const {
    if (static_cast<VkQueryPool>(*timestamps_) == VK_NULL_HANDLE) return -1.0;
    auto [result, stamps] = timestamps_.getResults<std::uint64_t>(0, 2, 2 * sizeof(std::uint64_t), sizeof(std::uint64_t),
                                                                 vk::QueryResultFlagBits::e64);
    if (result != vk::Result::eSuccess) return -1.0;
    const std::uint64_t ticks = (stamps[1] - stamps[0]) & timestamp_mask_;
    return static_cast<double>(ticks) * static_cast<double>(timestamp_period_ns_) * 1e-6;
}

Result<void> VulkanContext::submit(const std::function<void(const vk::raii::CommandBuffer&)>& record, double* gpu_ms) {
    const compute::Queue queue(*this);
    auto recording = queue.begin();
    if (!recording) return recording.error();
    record(vk_commands(recording.value()));
    auto submission = queue.submit(std::move(recording).value());
    if (!submission) return submission.error();
    return submission.value().wait(gpu_ms);
}

void VulkanContext::write_timestamp(const vk::raii::CommandBuffer& cmd, std::uint32_t which,
                                    vk::PipelineStageFlagBits stage) const {
    if (static_cast<VkQueryPool>(*timestamps_) != VK_NULL_HANDLE) cmd.writeTimestamp(stage, *timestamps_, which);
}

Result<std::uint32_t> VulkanContext::memory_type(std::uint32_t type_bits, vk::MemoryPropertyFlags required,
                                                 vk::MemoryPropertyFlags preferred) const {
    std::optional<std::uint32_t> fallback;
    for (std::uint32_t i = 0; i < memory_.memoryTypeCount; ++i) {
        if (!(type_bits & (1u << i))) continue;
        const auto flags = memory_.memoryTypes[i].propertyFlags;
        if ((flags & required) != required) continue;
        if ((flags & preferred) == preferred) return i;
        if (!fallback) fallback = i;
    }
    if (fallback) return *fallback;
    return make_error(Error::Kind::Vulkan, "no Vulkan memory type with the required properties " + vk::to_string(required));
}

}  // namespace kodawari::gpu
