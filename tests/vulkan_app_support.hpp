#pragma once
// An application's own Vulkan instance, device, command buffers and fences, in plain
// Vulkan, for the embedding tests (tests/backends/test_embedding.cpp, the C API's
// tests/capi/test_capi_embedding.cpp): they play the application that hands its device to
// Kodawari. Validation with synchronization validation is on when ctest asks
// (KODAWARI_VALIDATION=1); every message is a test failure.
#include <gtest/gtest.h>

#include <array>
#include <cstdint>
#include <vector>

#include <vulkan/vulkan.h>

#include "kodawari/vulkan/vulkan_embed.hpp"
#include "test_support.hpp"

namespace kodawari::testing_support {

inline std::uint32_t messages = 0;
inline VKAPI_ATTR VkBool32 VKAPI_CALL on_message(VkDebugUtilsMessageSeverityFlagBitsEXT severity, VkDebugUtilsMessageTypeFlagsEXT,
                                          const VkDebugUtilsMessengerCallbackDataEXT* data, void*) {
    if (severity >= VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT) {
        ++messages;
        ADD_FAILURE() << "validation: " << data->pMessage;
    }
    return VK_FALSE;
}

// The application: an instance and a device with one compute queue, plain Vulkan.
class Application {
public:
    Application() {
        const bool validation = testing_support::validation_requested();
        const VkApplicationInfo app{VK_STRUCTURE_TYPE_APPLICATION_INFO, nullptr, "test", 1, "test", 1, VK_API_VERSION_1_1};
        const char* layer = "VK_LAYER_KHRONOS_validation";
        const char* extension = VK_EXT_DEBUG_UTILS_EXTENSION_NAME;
        const VkValidationFeatureEnableEXT sync = VK_VALIDATION_FEATURE_ENABLE_SYNCHRONIZATION_VALIDATION_EXT;
        const VkValidationFeaturesEXT features{VK_STRUCTURE_TYPE_VALIDATION_FEATURES_EXT, nullptr, 1, &sync, 0, nullptr};
        const VkInstanceCreateInfo info{VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO, validation ? &features : nullptr, 0, &app,
                                        validation ? 1u : 0u, &layer, validation ? 1u : 0u, &extension};
        if (vkCreateInstance(&info, nullptr, &instance) != VK_SUCCESS) return;
        if (validation) {
            auto make = reinterpret_cast<PFN_vkCreateDebugUtilsMessengerEXT>(vkGetInstanceProcAddr(instance, "vkCreateDebugUtilsMessengerEXT"));
            const VkDebugUtilsMessengerCreateInfoEXT m{VK_STRUCTURE_TYPE_DEBUG_UTILS_MESSENGER_CREATE_INFO_EXT, nullptr, 0,
                                                       VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT | VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT,
                                                       VK_DEBUG_UTILS_MESSAGE_TYPE_GENERAL_BIT_EXT | VK_DEBUG_UTILS_MESSAGE_TYPE_VALIDATION_BIT_EXT,
                                                       &on_message, nullptr, };
            make(instance, &m, nullptr, &messenger);
        }
        std::uint32_t count = 1;
        if (vkEnumeratePhysicalDevices(instance, &count, &physical) < 0 || count == 0) return;
        std::uint32_t n = 0;
        vkGetPhysicalDeviceQueueFamilyProperties(physical, &n, nullptr);
        std::vector<VkQueueFamilyProperties> families(n);
        vkGetPhysicalDeviceQueueFamilyProperties(physical, &n, families.data());
        for (family = 0; family < n && !(families[family].queueFlags & VK_QUEUE_COMPUTE_BIT); ++family) {
        }
        const float priority = 1.0f;
        const VkDeviceQueueCreateInfo queue_info{VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO, nullptr, 0, family, 1, &priority};
        const VkDeviceCreateInfo device_info{VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO, nullptr, 0, 1, &queue_info, 0, nullptr, 0, nullptr, nullptr};
        if (vkCreateDevice(physical, &device_info, nullptr, &device) != VK_SUCCESS) return;
        vkGetDeviceQueue(device, family, 0, &queue);
        const VkCommandPoolCreateInfo pool_info{VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO, nullptr,
                                                VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT, family};
        vkCreateCommandPool(device, &pool_info, nullptr, &pool);
        const VkCommandBufferAllocateInfo alloc{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO, nullptr, pool,
                                                VK_COMMAND_BUFFER_LEVEL_PRIMARY, kInFlight};
        vkAllocateCommandBuffers(device, &alloc, cmds.data());
        for (VkFence& f : fences) {
            const VkFenceCreateInfo fence{VK_STRUCTURE_TYPE_FENCE_CREATE_INFO, nullptr, VK_FENCE_CREATE_SIGNALED_BIT};
            vkCreateFence(device, &fence, nullptr, &f);
        }
    }
    Application(const Application&) = delete;
    Application& operator=(const Application&) = delete;
    ~Application() {
        if (device != VK_NULL_HANDLE) {
            vkDeviceWaitIdle(device);
            for (VkFence f : fences) vkDestroyFence(device, f, nullptr);
            vkDestroyCommandPool(device, pool, nullptr);
            vkDestroyDevice(device, nullptr);  // still valid: the module destroyed nothing of ours
        }
        if (messenger != VK_NULL_HANDLE) {
            auto destroy = reinterpret_cast<PFN_vkDestroyDebugUtilsMessengerEXT>(vkGetInstanceProcAddr(instance, "vkDestroyDebugUtilsMessengerEXT"));
            destroy(instance, messenger, nullptr);
        }
        if (instance != VK_NULL_HANDLE) vkDestroyInstance(instance, nullptr);
    }

    [[nodiscard]] bool ok() const { return device != VK_NULL_HANDLE && pool != VK_NULL_HANDLE; }
    [[nodiscard]] VulkanDeviceHandles handles() const {
        return {.instance = instance,
                .physical_device = physical,
                .device = device,
                .queue_family = family,
                .queue_index = 0,
                .get_instance_proc_addr = vkGetInstanceProcAddr,
                .allocator = nullptr,
                .api_version = VK_API_VERSION_1_1,
                .frames_in_flight = kInFlight};
    }
    // Frame k's command buffer, once the GPU finished frame k - kInFlight (its fence).
    VkCommandBuffer begin(std::uint32_t k) {
        const std::uint32_t slot = k % kInFlight;
        vkWaitForFences(device, 1, &fences[slot], VK_TRUE, UINT64_MAX);
        vkResetFences(device, 1, &fences[slot]);
        vkResetCommandBuffer(cmds[slot], 0);
        const VkCommandBufferBeginInfo begin{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO, nullptr, VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT, nullptr};
        vkBeginCommandBuffer(cmds[slot], &begin);
        return cmds[slot];
    }
    void submit(std::uint32_t k) {
        const std::uint32_t slot = k % kInFlight;
        vkEndCommandBuffer(cmds[slot]);
        const VkSubmitInfo submit{VK_STRUCTURE_TYPE_SUBMIT_INFO, nullptr, 0, nullptr, nullptr, 1, &cmds[slot], 0, nullptr};
        ASSERT_EQ(vkQueueSubmit(queue, 1, &submit, fences[slot]), VK_SUCCESS);
    }
    void wait_all() { vkWaitForFences(device, kInFlight, fences.data(), VK_TRUE, UINT64_MAX); }

    static constexpr std::uint32_t kInFlight = 3;
    VkInstance instance = VK_NULL_HANDLE;
    VkDebugUtilsMessengerEXT messenger = VK_NULL_HANDLE;
    VkPhysicalDevice physical = VK_NULL_HANDLE;
    VkDevice device = VK_NULL_HANDLE;
    std::uint32_t family = 0;
    VkQueue queue = VK_NULL_HANDLE;
    VkCommandPool pool = VK_NULL_HANDLE;
    std::array<VkCommandBuffer, kInFlight> cmds{};
    std::array<VkFence, kInFlight> fences{};
};


}  // namespace kodawari::testing_support
