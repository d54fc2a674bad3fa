// The C API's device embedding (kodawari.h, "Device embedding"): the application's Vulkan
// device wrapped for the worlds' backend options. Recording and the buffers' ranges are in
// capi_rods.cpp and capi_birds.cpp, next to the worlds they belong to.
#include <string>
#include <string_view>

#include <vulkan/vulkan_core.h>

#include "capi/capi_common.hpp"
#include "kodawari/vulkan/vulkan_embed.hpp"

using namespace kodawari;
using namespace kodawari::capi;

extern "C" {

KODAWARI_C_API kodawari_status kodawari_vulkan_device_adopt(const kodawari_vulkan_device_desc* desc,
                                                            kodawari_vulkan_device** out) {
    return guard("kodawari_vulkan_device_adopt", nullptr, [&] {
        require_pointer(out, "out");
        *out = nullptr;
        require_pointer(desc, "desc");
        VulkanDeviceHandles handles;
        handles.instance = static_cast<VkInstance>(desc->instance);
        handles.physical_device = static_cast<VkPhysicalDevice>(desc->physical_device);
        handles.device = static_cast<VkDevice>(desc->device);
        handles.queue_family = desc->queue_family;
        handles.queue_index = desc->queue_index;
        handles.get_instance_proc_addr = reinterpret_cast<PFN_vkGetInstanceProcAddr>(desc->get_instance_proc_addr);
        handles.allocator = static_cast<const VkAllocationCallbacks*>(desc->allocator);
        handles.api_version = desc->api_version;
        handles.frames_in_flight = desc->frames_in_flight;
        auto adopted = adopt_vulkan_device(handles);
        if (!adopted) {
            // The C++ struct's members are the C desc's fields: name those.
            Error error = adopted.error();
            for (std::size_t at; (at = error.message.find("VulkanDeviceHandles::")) != std::string::npos;) {
                error.message.replace(at, std::string_view("VulkanDeviceHandles::").size(), "desc->");
            }
            fail(error);
        }
        auto device = std::make_unique<kodawari_vulkan_device>();
        device->context = std::move(adopted).value();
        *out = device.release();
    });
}

KODAWARI_C_API void kodawari_vulkan_device_release(kodawari_vulkan_device* device) { delete device; }

}  // extern "C"
