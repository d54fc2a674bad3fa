// An application with its own Vulkan instance, device, command buffers and drawing, using
// Kodawari as a compute module (docs/embedding.md walks through this file):
//
//   1. it creates its instance and device as it always does, and hands them to
//      kodawari::adopt_vulkan_device();
//   2. it makes a vulkan rod backend (a crowd of strands) and a Simulation of a flocking
//      flock (a scene in a string: birds that fly by their neighbours) on it;
//   3. each frame, with two frames in flight, it moves a hawk of its own through the flock
//      (written on the device, into the buffer the module reads its agents from:
//      set_flock_device_agents), records the module's chain step and the flock's frame into
//      its own command buffer, then draws joints and birds as points straight from the
//      module's buffers (its own shaders, the module's struct definitions), offscreen;
//   4. at the end it checks that the drawn points are where a read-back of the same state
//      puts them (the flock: a second Simulation stepped with the same hawk), and that the
//      validation layers (with synchronization validation) said nothing.
//
//   embed_vulkan [--validation] [--frames N] [--png OUT.ppm]
//
// Exit status 0 when every check passes. A wrong barrier shows as a validation message,
// a wrong offset or layout as points in the wrong place.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include <glm/glm.hpp>
#include <vulkan/vulkan.h>

#include <kodawari/vulkan/backend_factory.hpp>
#include <kodawari/domains/birds.hpp>
#include <kodawari/domains/flocking.hpp>
#include <kodawari/rods/synthetic.hpp>
#include <kodawari/scene/scene.hpp>
#include <kodawari/simulation/simulation.hpp>
#include <kodawari/shared/birds.h>
#include <kodawari/shared/rods.h>
#include <kodawari/core/version.hpp>
#include <kodawari/vulkan/vulkan_embed.hpp>

#include "points.frag.spv.h"
#include "points.vert.spv.h"

namespace {

constexpr std::uint32_t kWidth = 320, kHeight = 160;  // left half: chains, right half: birds
constexpr std::uint32_t kFramesInFlight = 2;
constexpr std::uint32_t kChains = 123;  // not a multiple of the kernels' workgroup sizes
constexpr std::uint32_t kJoints = 8;
constexpr std::uint32_t kBirds = 301;

[[noreturn]] void fail(const std::string& what) {
    std::fprintf(stderr, "embed_vulkan: %s\n", what.c_str());
    std::exit(1);
}
void check(VkResult result, const char* what) {
    if (result != VK_SUCCESS) fail(std::string(what) + " failed (VkResult " + std::to_string(result) + ")");
}
template <typename T>
T value_of(kodawari::Result<T> result, const char* what) {
    if (!result) fail(std::string(what) + ": " + result.error().message);
    return std::move(result).value();
}
void ok_or_fail(const kodawari::Result<void>& result, const char* what) {
    if (!result) fail(std::string(what) + ": " + result.error().message);
}

std::uint32_t validation_messages = 0;
VKAPI_ATTR VkBool32 VKAPI_CALL on_message(VkDebugUtilsMessageSeverityFlagBitsEXT severity, VkDebugUtilsMessageTypeFlagsEXT,
                                          const VkDebugUtilsMessengerCallbackDataEXT* data, void*) {
    if (severity >= VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT) {
        ++validation_messages;
        std::fprintf(stderr, "[validation] %s\n", data->pMessage);
    }
    return VK_FALSE;
}

// The application's own Vulkan setup: what any engine already has.
struct App {
    VkInstance instance = VK_NULL_HANDLE;
    VkDebugUtilsMessengerEXT messenger = VK_NULL_HANDLE;
    VkPhysicalDevice physical = VK_NULL_HANDLE;
    VkDevice device = VK_NULL_HANDLE;
    std::uint32_t family = 0;
    VkQueue queue = VK_NULL_HANDLE;
    VkPhysicalDeviceMemoryProperties memory{};

    std::uint32_t memory_type(std::uint32_t bits, VkMemoryPropertyFlags flags) const {
        for (std::uint32_t i = 0; i < memory.memoryTypeCount; ++i) {
            if ((bits & (1u << i)) && (memory.memoryTypes[i].propertyFlags & flags) == flags) return i;
        }
        fail("no memory type");
    }
};

App create_app(bool validation) {
    App app;
    const VkApplicationInfo info{VK_STRUCTURE_TYPE_APPLICATION_INFO, nullptr, "embed_vulkan", 1, "an engine", 1, VK_API_VERSION_1_1};
    const char* layer = "VK_LAYER_KHRONOS_validation";
    const char* extension = VK_EXT_DEBUG_UTILS_EXTENSION_NAME;
    const VkValidationFeatureEnableEXT sync = VK_VALIDATION_FEATURE_ENABLE_SYNCHRONIZATION_VALIDATION_EXT;
    const VkValidationFeaturesEXT features{VK_STRUCTURE_TYPE_VALIDATION_FEATURES_EXT, nullptr, 1, &sync, 0, nullptr};
    const VkInstanceCreateInfo create{VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO, validation ? &features : nullptr, 0, &info,
                                      validation ? 1u : 0u, &layer, validation ? 1u : 0u, &extension};
    check(vkCreateInstance(&create, nullptr, &app.instance), "vkCreateInstance (with --validation: is vulkan-validationlayers installed?)");
    if (validation) {
        auto make = reinterpret_cast<PFN_vkCreateDebugUtilsMessengerEXT>(vkGetInstanceProcAddr(app.instance, "vkCreateDebugUtilsMessengerEXT"));
        const VkDebugUtilsMessengerCreateInfoEXT messenger{
            VK_STRUCTURE_TYPE_DEBUG_UTILS_MESSENGER_CREATE_INFO_EXT, nullptr, 0,
            VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT | VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT,
            VK_DEBUG_UTILS_MESSAGE_TYPE_GENERAL_BIT_EXT | VK_DEBUG_UTILS_MESSAGE_TYPE_VALIDATION_BIT_EXT |
                VK_DEBUG_UTILS_MESSAGE_TYPE_PERFORMANCE_BIT_EXT,
            &on_message, nullptr};
        check(make(app.instance, &messenger, nullptr, &app.messenger), "vkCreateDebugUtilsMessengerEXT");
    }
    std::uint32_t count = 0;
    vkEnumeratePhysicalDevices(app.instance, &count, nullptr);
    if (count == 0) {
        // The one reason to skip (ctest's SKIP_RETURN_CODE): no device at all.
        std::fprintf(stderr, "embed_vulkan: skipped: the Vulkan loader found no device (install Mesa's lavapipe)\n");
        std::exit(77);
    }
    std::vector<VkPhysicalDevice> devices(count);
    vkEnumeratePhysicalDevices(app.instance, &count, devices.data());
    // The first device with a family that draws and computes: one queue for both.
    for (VkPhysicalDevice d : devices) {
        std::uint32_t n = 0;
        vkGetPhysicalDeviceQueueFamilyProperties(d, &n, nullptr);
        std::vector<VkQueueFamilyProperties> families(n);
        vkGetPhysicalDeviceQueueFamilyProperties(d, &n, families.data());
        for (std::uint32_t f = 0; f < n && app.physical == VK_NULL_HANDLE; ++f) {
            const VkQueueFlags both = VK_QUEUE_GRAPHICS_BIT | VK_QUEUE_COMPUTE_BIT;
            if ((families[f].queueFlags & both) == both) {
                app.physical = d;
                app.family = f;
            }
        }
    }
    if (app.physical == VK_NULL_HANDLE) fail("no device with a graphics + compute queue family");
    vkGetPhysicalDeviceMemoryProperties(app.physical, &app.memory);
    const float priority = 1.0f;
    const VkDeviceQueueCreateInfo queue{VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO, nullptr, 0, app.family, 1, &priority};
    const VkDeviceCreateInfo device{VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO, nullptr, 0, 1, &queue, 0, nullptr, 0, nullptr, nullptr};
    check(vkCreateDevice(app.physical, &device, nullptr, &app.device), "vkCreateDevice");
    vkGetDeviceQueue(app.device, app.family, 0, &app.queue);
    return app;
}

struct HostBuffer {
    VkBuffer buffer = VK_NULL_HANDLE;
    VkDeviceMemory memory = VK_NULL_HANDLE;
    void* mapped = nullptr;
};
HostBuffer make_readback(const App& app, VkDeviceSize size) {
    HostBuffer out;
    const VkBufferCreateInfo info{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO, nullptr, 0, size, VK_BUFFER_USAGE_TRANSFER_DST_BIT,
                                  VK_SHARING_MODE_EXCLUSIVE, 0, nullptr};
    check(vkCreateBuffer(app.device, &info, nullptr, &out.buffer), "vkCreateBuffer");
    VkMemoryRequirements needs;
    vkGetBufferMemoryRequirements(app.device, out.buffer, &needs);
    const VkMemoryAllocateInfo alloc{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO, nullptr, needs.size,
                                     app.memory_type(needs.memoryTypeBits, VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT)};
    check(vkAllocateMemory(app.device, &alloc, nullptr, &out.memory), "vkAllocateMemory");
    check(vkBindBufferMemory(app.device, out.buffer, out.memory, 0), "vkBindBufferMemory");
    check(vkMapMemory(app.device, out.memory, 0, VK_WHOLE_SIZE, 0, &out.mapped), "vkMapMemory");
    return out;
}

struct Target {
    VkImage image = VK_NULL_HANDLE;
    VkDeviceMemory memory = VK_NULL_HANDLE;
    VkImageView view = VK_NULL_HANDLE;
    VkFramebuffer framebuffer = VK_NULL_HANDLE;
    HostBuffer pixels;
};

VkShaderModule shader(VkDevice device, const std::uint32_t* code, std::size_t bytes) {
    const VkShaderModuleCreateInfo info{VK_STRUCTURE_TYPE_SHADER_MODULE_CREATE_INFO, nullptr, 0, bytes, code};
    VkShaderModule module = VK_NULL_HANDLE;
    check(vkCreateShaderModule(device, &info, nullptr, &module), "vkCreateShaderModule");
    return module;
}

struct Push {
    glm::mat4 view_proj;
    std::uint32_t info[4];
    float color[4];
};

// An orthographic view of two world axes onto one half of the image, fitted to `points`
// with a margin (the state moves a little over the frames).
struct View {
    glm::mat4 view_proj{1.0f};
    int axis_x = 0, axis_y = 1;
    std::uint32_t x0 = 0;  // the half's first pixel column
};
View fit(const std::vector<glm::vec3>& points, int axis_x, int axis_y, std::uint32_t x0) {
    glm::vec2 lo(1e30f), hi(-1e30f);
    for (const glm::vec3& p : points) {
        lo = glm::min(lo, glm::vec2(p[axis_x], p[axis_y]));
        hi = glm::max(hi, glm::vec2(p[axis_x], p[axis_y]));
    }
    const glm::vec2 centre = 0.5f * (lo + hi);
    const glm::vec2 half = glm::max(0.5f * (hi - lo) * 1.3f, glm::vec2(1e-3f));
    View v;
    v.axis_x = axis_x;
    v.axis_y = axis_y;
    v.x0 = x0;
    glm::mat4 m(0.0f);
    // clip.x = (p[ax] - c.x) / h.x, clip.y = -(p[ay] - c.y) / h.y (Vulkan's y points down), z = 0.5.
    m[axis_x][0] = 1.0f / half.x;
    m[axis_y][1] = -1.0f / half.y;
    m[3][0] = -centre.x / half.x;
    m[3][1] = centre.y / half.y;
    m[3][2] = 0.5f;
    m[3][3] = 1.0f;
    v.view_proj = m;
    return v;
}

// Counts the expected points found drawn (a pixel of `color` within one pixel of where the
// read-back state projects), and the pixels of that colour in the half.
struct Match {
    std::uint32_t inside = 0, found = 0, lit = 0;
};
Match match(const View& view, const std::vector<glm::vec3>& points, const std::uint8_t* rgba, int channel) {
    Match m;
    const std::uint32_t half = kWidth / 2;
    auto lit = [&](int x, int y) {
        if (x < 0 || y < 0 || x >= static_cast<int>(half) || y >= static_cast<int>(kHeight)) return false;
        return rgba[(static_cast<std::size_t>(y) * kWidth + view.x0 + static_cast<std::size_t>(x)) * 4 + channel] > 128;
    };
    for (const glm::vec3& p : points) {
        const glm::vec4 clip = view.view_proj * glm::vec4(p, 1.0f);
        const float sx = (clip.x * 0.5f + 0.5f) * static_cast<float>(half), sy = (clip.y * 0.5f + 0.5f) * static_cast<float>(kHeight);
        if (sx < 1.0f || sy < 1.0f || sx > static_cast<float>(half) - 1.0f || sy > static_cast<float>(kHeight) - 1.0f) continue;
        ++m.inside;
        const int px = static_cast<int>(sx), py = static_cast<int>(sy);
        bool hit = false;
        for (int dy = -1; dy <= 1 && !hit; ++dy) {
            for (int dx = -1; dx <= 1 && !hit; ++dx) hit = lit(px + dx, py + dy);
        }
        if (hit) ++m.found;
    }
    for (std::uint32_t y = 0; y < kHeight; ++y) {
        for (std::uint32_t x = 0; x < half; ++x) m.lit += lit(static_cast<int>(x), static_cast<int>(y)) ? 1 : 0;
    }
    return m;
}

// A flocking flock over a field, as a scene file would have it (docs/scene-format.md):
// 301 birds that fly by their seven nearest neighbours, drawn to a looping route.
constexpr const char* kFlockScene = R"({"format": "kodawari-scene", "version": 1, "name": "embedded flock", "fps": 60,
    "duration": 10, "camera": {"position": [0, 60, -120], "target": [0, 20, 0], "fov_deg": 60},
    "flocks": [{"name": "starlings", "wing_type": "pigeon", "count": 301, "seed": 3, "speed": 12,
                "generated_route": {"seed": 7, "segments": 6, "center": [0, 20, 0], "extent": [35, 6, 35], "loop": true},
                "formation": {"spread": [10, 4, 10]}, "flocking": {}}]})";

// The application's hawk at frame k: through where the flock starts, 30 m/s along x.
kodawari::FlockAgent hawk_at(std::uint32_t k, const glm::vec3& start) {
    kodawari::FlockAgent hawk;
    hawk.kind = kodawari::FlockAgent::Kind::Predator;
    hawk.velocity = {30.0f, 0.0f, 0.0f};
    hawk.position = start + glm::vec3(-6.0f + 0.5f * static_cast<float>(k), 0.0f, 0.0f);
    hawk.radius = 12.0f;
    hawk.weight = 60.0f;
    return hawk;
}

}  // namespace

int main(int argc, char** argv) {
    bool validation = false;
    std::uint32_t frames = 12;
    const char* image_out = nullptr;
    for (int i = 1; i < argc; ++i) {
        const std::string arg = argv[i];
        if (arg == "--validation") {
            validation = true;
        } else if (arg == "--frames" && i + 1 < argc) {
            frames = static_cast<std::uint32_t>(std::max(1, std::atoi(argv[++i])));
        } else if (arg == "--image" && i + 1 < argc) {
            image_out = argv[++i];
        } else {
            fail("usage: embed_vulkan [--validation] [--frames N] [--image OUT.ppm]");
        }
    }
    std::printf("kodawari %s, embedded\n", std::string(kodawari::version()).c_str());
    App app = create_app(validation);

    // --- Kodawari on the application's device ----------------------------------------
    auto device = value_of(kodawari::adopt_vulkan_device({.instance = app.instance,
                                                          .physical_device = app.physical,
                                                          .device = app.device,
                                                          .queue_family = app.family,
                                                          .queue_index = 0,
                                                          .get_instance_proc_addr = vkGetInstanceProcAddr,
                                                          .allocator = nullptr,
                                                          .api_version = VK_API_VERSION_1_1,
                                                          .frames_in_flight = kFramesInFlight}),
                           "adopt_vulkan_device");
    kodawari::BackendOptions options{.context = device};
    auto scene = value_of(kodawari::rods::SyntheticScene::make({.chains = kChains, .joints = kJoints, .iterations = 4,
                                                                .chains_per_character = 7, .views = 3}),
                          "the chains");
    const kodawari::rods::RodWorld& world = scene.world();
    for (std::uint32_t c = 0; c < kChains; ++c) {
        if (world.chains[c].joint_begin != c * kJoints) fail("the shader's joint-to-chain rule does not hold");
    }
    auto rods = value_of(kodawari::make_rod_backend(kodawari::BackendKind::Vulkan, options), "make_rod_backend");
    constexpr float kDt = 1.0f / 60.0f;
    kodawari::rods::RodFrame frame;
    scene.frame(0, kDt, frame);
    ok_or_fail(rods->load(world, frame), "rods load");  // uploads once, on the application's queue

    // The flock: a Simulation of its scene on the same device (no file needed), recorded
    // frame by frame with Simulation::record; a second one is stepped the usual way with
    // the same hawk, to check against.
    const auto open_flock = [&] {
        kodawari::SimulationOptions flock_options{.backend = kodawari::BackendKind::Vulkan, .options = options};
        auto flock_scene = value_of(kodawari::parse_scene(kFlockScene, "embedded-flock.json"), "the flock's scene");
        return value_of(kodawari::Simulation::create(std::move(flock_scene), flock_options), "the flock's Simulation");
    };
    std::unique_ptr<kodawari::Simulation> flock = open_flock();
    const kodawari::birds::BirdWorld& flock_world = kodawari::bird_world(*flock);
    if (flock_world.birds.size() != kBirds) fail("the flock's scene has another bird count");

    // --- The application's drawing -------------------------------------------------------
    const VkAttachmentDescription color{0, VK_FORMAT_R8G8B8A8_UNORM, VK_SAMPLE_COUNT_1_BIT, VK_ATTACHMENT_LOAD_OP_CLEAR,
                                        VK_ATTACHMENT_STORE_OP_STORE, VK_ATTACHMENT_LOAD_OP_DONT_CARE, VK_ATTACHMENT_STORE_OP_DONT_CARE,
                                        VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL};
    const VkAttachmentReference color_ref{0, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL};
    const VkSubpassDescription subpass{0, VK_PIPELINE_BIND_POINT_GRAPHICS, 0, nullptr, 1, &color_ref, nullptr, nullptr, 0, nullptr};
    // The copy of the previous use of the image before this frame clears it; this frame's
    // writes before its copy. (The module's barriers order its buffers; these order ours.)
    const VkSubpassDependency dependencies[2] = {
        {VK_SUBPASS_EXTERNAL, 0, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT, 0,
         VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT, 0},
        {0, VK_SUBPASS_EXTERNAL, VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT, VK_PIPELINE_STAGE_TRANSFER_BIT,
         VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT, VK_ACCESS_TRANSFER_READ_BIT, 0}};
    const VkRenderPassCreateInfo pass_info{VK_STRUCTURE_TYPE_RENDER_PASS_CREATE_INFO, nullptr, 0, 1, &color, 1, &subpass, 2, dependencies};
    VkRenderPass pass = VK_NULL_HANDLE;
    check(vkCreateRenderPass(app.device, &pass_info, nullptr, &pass), "vkCreateRenderPass");

    VkDescriptorSetLayoutBinding bindings[3];
    for (std::uint32_t b = 0; b < 3; ++b) {
        bindings[b] = {b, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1, VK_SHADER_STAGE_VERTEX_BIT, nullptr};
    }
    const VkDescriptorSetLayoutCreateInfo set_info{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO, nullptr, 0, 3, bindings};
    VkDescriptorSetLayout set_layout = VK_NULL_HANDLE;
    check(vkCreateDescriptorSetLayout(app.device, &set_info, nullptr, &set_layout), "vkCreateDescriptorSetLayout");
    const VkPushConstantRange push_range{VK_SHADER_STAGE_VERTEX_BIT, 0, sizeof(Push)};
    const VkPipelineLayoutCreateInfo layout_info{VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO, nullptr, 0, 1, &set_layout, 1, &push_range};
    VkPipelineLayout layout = VK_NULL_HANDLE;
    check(vkCreatePipelineLayout(app.device, &layout_info, nullptr, &layout), "vkCreatePipelineLayout");

    const VkShaderModule vert = shader(app.device, points_vert, sizeof(points_vert));
    const VkShaderModule frag = shader(app.device, points_frag, sizeof(points_frag));
    const VkPipelineShaderStageCreateInfo stages[2] = {
        {VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO, nullptr, 0, VK_SHADER_STAGE_VERTEX_BIT, vert, "main", nullptr},
        {VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO, nullptr, 0, VK_SHADER_STAGE_FRAGMENT_BIT, frag, "main", nullptr}};
    const VkPipelineVertexInputStateCreateInfo vertex_input{.sType = VK_STRUCTURE_TYPE_PIPELINE_VERTEX_INPUT_STATE_CREATE_INFO};
    const VkPipelineInputAssemblyStateCreateInfo assembly{VK_STRUCTURE_TYPE_PIPELINE_INPUT_ASSEMBLY_STATE_CREATE_INFO, nullptr, 0,
                                                          VK_PRIMITIVE_TOPOLOGY_POINT_LIST, VK_FALSE};
    const VkPipelineViewportStateCreateInfo viewport_state{VK_STRUCTURE_TYPE_PIPELINE_VIEWPORT_STATE_CREATE_INFO, nullptr, 0, 1, nullptr, 1, nullptr};
    VkPipelineRasterizationStateCreateInfo raster{.sType = VK_STRUCTURE_TYPE_PIPELINE_RASTERIZATION_STATE_CREATE_INFO};
    raster.polygonMode = VK_POLYGON_MODE_FILL;
    raster.cullMode = VK_CULL_MODE_NONE;
    raster.lineWidth = 1.0f;
    VkPipelineMultisampleStateCreateInfo multisample{.sType = VK_STRUCTURE_TYPE_PIPELINE_MULTISAMPLE_STATE_CREATE_INFO};
    multisample.rasterizationSamples = VK_SAMPLE_COUNT_1_BIT;
    VkPipelineColorBlendAttachmentState blend_attachment{};
    blend_attachment.colorWriteMask = VK_COLOR_COMPONENT_R_BIT | VK_COLOR_COMPONENT_G_BIT | VK_COLOR_COMPONENT_B_BIT | VK_COLOR_COMPONENT_A_BIT;
    VkPipelineColorBlendStateCreateInfo blend{.sType = VK_STRUCTURE_TYPE_PIPELINE_COLOR_BLEND_STATE_CREATE_INFO};
    blend.attachmentCount = 1;
    blend.pAttachments = &blend_attachment;
    const VkDynamicState dynamic[2] = {VK_DYNAMIC_STATE_VIEWPORT, VK_DYNAMIC_STATE_SCISSOR};
    const VkPipelineDynamicStateCreateInfo dynamic_state{VK_STRUCTURE_TYPE_PIPELINE_DYNAMIC_STATE_CREATE_INFO, nullptr, 0, 2, dynamic};
    VkGraphicsPipelineCreateInfo pipeline_info{.sType = VK_STRUCTURE_TYPE_GRAPHICS_PIPELINE_CREATE_INFO};
    pipeline_info.stageCount = 2;
    pipeline_info.pStages = stages;
    pipeline_info.pVertexInputState = &vertex_input;
    pipeline_info.pInputAssemblyState = &assembly;
    pipeline_info.pViewportState = &viewport_state;
    pipeline_info.pRasterizationState = &raster;
    pipeline_info.pMultisampleState = &multisample;
    pipeline_info.pColorBlendState = &blend;
    pipeline_info.pDynamicState = &dynamic_state;
    pipeline_info.layout = layout;
    pipeline_info.renderPass = pass;
    VkPipeline pipeline = VK_NULL_HANDLE;
    check(vkCreateGraphicsPipelines(app.device, VK_NULL_HANDLE, 1, &pipeline_info, nullptr, &pipeline), "vkCreateGraphicsPipelines");

    const VkDescriptorPoolSize pool_size{VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 3};
    const VkDescriptorPoolCreateInfo pool_info{VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO, nullptr, 0, 1, 1, &pool_size};
    VkDescriptorPool descriptor_pool = VK_NULL_HANDLE;
    check(vkCreateDescriptorPool(app.device, &pool_info, nullptr, &descriptor_pool), "vkCreateDescriptorPool");
    const VkDescriptorSetAllocateInfo set_alloc{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO, nullptr, descriptor_pool, 1, &set_layout};
    VkDescriptorSet set = VK_NULL_HANDLE;
    check(vkAllocateDescriptorSets(app.device, &set_alloc, &set), "vkAllocateDescriptorSets");

    std::array<Target, kFramesInFlight> targets;
    for (Target& t : targets) {
        VkImageCreateInfo image{.sType = VK_STRUCTURE_TYPE_IMAGE_CREATE_INFO};
        image.imageType = VK_IMAGE_TYPE_2D;
        image.format = VK_FORMAT_R8G8B8A8_UNORM;
        image.extent = {kWidth, kHeight, 1};
        image.mipLevels = 1;
        image.arrayLayers = 1;
        image.samples = VK_SAMPLE_COUNT_1_BIT;
        image.tiling = VK_IMAGE_TILING_OPTIMAL;
        image.usage = VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT;
        check(vkCreateImage(app.device, &image, nullptr, &t.image), "vkCreateImage");
        VkMemoryRequirements needs;
        vkGetImageMemoryRequirements(app.device, t.image, &needs);
        const VkMemoryAllocateInfo alloc{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO, nullptr, needs.size,
                                         app.memory_type(needs.memoryTypeBits, VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT)};
        check(vkAllocateMemory(app.device, &alloc, nullptr, &t.memory), "vkAllocateMemory");
        check(vkBindImageMemory(app.device, t.image, t.memory, 0), "vkBindImageMemory");
        const VkImageViewCreateInfo view{VK_STRUCTURE_TYPE_IMAGE_VIEW_CREATE_INFO, nullptr, 0, t.image, VK_IMAGE_VIEW_TYPE_2D,
                                         VK_FORMAT_R8G8B8A8_UNORM, {}, {VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1}};
        check(vkCreateImageView(app.device, &view, nullptr, &t.view), "vkCreateImageView");
        const VkFramebufferCreateInfo fb{VK_STRUCTURE_TYPE_FRAMEBUFFER_CREATE_INFO, nullptr, 0, pass, 1, &t.view, kWidth, kHeight, 1};
        check(vkCreateFramebuffer(app.device, &fb, nullptr, &t.framebuffer), "vkCreateFramebuffer");
        t.pixels = make_readback(app, VkDeviceSize{kWidth} * kHeight * 4);
    }

    const VkCommandPoolCreateInfo cmd_pool_info{VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO, nullptr,
                                                VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT, app.family};
    VkCommandPool cmd_pool = VK_NULL_HANDLE;
    check(vkCreateCommandPool(app.device, &cmd_pool_info, nullptr, &cmd_pool), "vkCreateCommandPool");
    std::array<VkCommandBuffer, kFramesInFlight> cmds{};
    const VkCommandBufferAllocateInfo cmd_alloc{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO, nullptr, cmd_pool,
                                                VK_COMMAND_BUFFER_LEVEL_PRIMARY, kFramesInFlight};
    check(vkAllocateCommandBuffers(app.device, &cmd_alloc, cmds.data()), "vkAllocateCommandBuffers");
    std::array<VkFence, kFramesInFlight> fences{};
    for (VkFence& f : fences) {
        const VkFenceCreateInfo info{VK_STRUCTURE_TYPE_FENCE_CREATE_INFO, nullptr, VK_FENCE_CREATE_SIGNALED_BIT};
        check(vkCreateFence(app.device, &info, nullptr, &f), "vkCreateFence");
    }

    // Views fitted to the initial state: the chains from the front (x, y), the flock from
    // above (x, z) over its route.
    kodawari::ChainSnapshot snapshot;
    ok_or_fail(rods->read(snapshot), "rods read");
    const View chain_view = fit(snapshot.positions, 0, 1, 0);
    std::vector<glm::vec3> route_points;
    for (const kodawari::gpu::vec4& p : flock_world.control_points) route_points.push_back({p.x, p.y, p.z});
    if (flock_world.control_points.empty()) fail("the flock's route has no points");
    const kodawari::gpu::vec4 first_point = flock_world.control_points[0];
    const glm::vec3 route_start(first_point.x, first_point.y, first_point.z);
    // Flocking birds trail their route's leader by up to some 20 m (docs/flocking.md) and
    // scatter from the hawk: the view takes the route's box grown by 25 m.
    glm::vec3 lo = route_start, hi = route_start;
    for (const glm::vec3& p : route_points) lo = glm::min(lo, p), hi = glm::max(hi, p);
    const View bird_view = fit({lo - glm::vec3(25.0f), hi + glm::vec3(25.0f)}, 0, 2, kWidth / 2);

    // --- The frame loop: two frames in flight ----------------------------------------------
    std::uint32_t first_bird = 0;
    // The hawk is the application's: it writes it on the device each frame, where the
    // flock's step reads its agents (one agent, the first of the range handed out).
    ok_or_fail(kodawari::set_flock_device_agents(*flock, 1), "set_flock_device_agents");
    const auto agents = value_of(flock->buffer(kodawari::flock_buffers::agents), "flocking.agents");
    for (std::uint32_t k = 1; k <= frames; ++k) {
        const std::uint32_t slot = k % kFramesInFlight;
        const kodawari::gpu::FlockAgentGpu hawk = value_of(kodawari::encode_flock_agent(hawk_at(k, route_start)), "hawk");
        check(vkWaitForFences(app.device, 1, &fences[slot], VK_TRUE, UINT64_MAX), "vkWaitForFences");
        check(vkResetFences(app.device, 1, &fences[slot]), "vkResetFences");
        VkCommandBuffer cmd = cmds[slot];
        check(vkResetCommandBuffer(cmd, 0), "vkResetCommandBuffer");
        const VkCommandBufferBeginInfo begin{.sType = VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO, .flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT};
        check(vkBeginCommandBuffer(cmd, &begin), "vkBeginCommandBuffer");

        scene.frame(k, kDt, frame);
        // The hawk, where a kernel of the application's would write it: after the previous
        // frame's step read the agents (a barrier from compute-shader reads), before this
        // frame's, which makes the write visible to itself.
        const VkMemoryBarrier after_reads{VK_STRUCTURE_TYPE_MEMORY_BARRIER, nullptr, 0, 0};
        vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_PIPELINE_STAGE_TRANSFER_BIT, 0, 1, &after_reads, 0,
                             nullptr, 0, nullptr);
        vkCmdUpdateBuffer(cmd, agents.buffer, agents.offset, sizeof hawk, &hawk);
        // The module's work, then the draws that read it, with no barrier of the
        // application's in between (the module records them: docs/embedding.md).
        ok_or_fail(flock->record(cmd), "Simulation::record");
        ok_or_fail(kodawari::record_step(*rods, cmd, frame), "record_step");

        // Where this frame's results are: bound once (the ranges do not move), the bird
        // slot passed as an element index (an offset need not meet the descriptor
        // alignment).
        const auto states = value_of(kodawari::vulkan_buffer(*rods->device_data(), kodawari::rod_buffers::chain_states), "states");
        const auto motion = value_of(kodawari::vulkan_buffer(*rods->device_data(), kodawari::rod_buffers::motion), "motion");
        const auto poses = value_of(flock->buffer(kodawari::bird_buffers::poses), "birds.poses");
        if (motion.stride != sizeof(kodawari::gpu::RodJointMotionGpu) || poses.stride != sizeof(kodawari::gpu::BirdPoseGpu)) {
            fail("the module's strides differ from its structs");
        }
        first_bird = static_cast<std::uint32_t>(poses.offset / poses.stride);
        if (k == 1) {
            const VkDescriptorBufferInfo infos[3] = {{states.buffer, states.offset, states.range},
                                                     {motion.buffer, motion.offset, motion.range},
                                                     {poses.buffer, 0, VK_WHOLE_SIZE}};
            VkWriteDescriptorSet writes[3];
            for (std::uint32_t b = 0; b < 3; ++b) {
                writes[b] = {VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET, nullptr, set, b, 0, 1, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, nullptr, &infos[b], nullptr};
            }
            vkUpdateDescriptorSets(app.device, 3, writes, 0, nullptr);
        }

        const Target& target = targets[slot];
        const VkClearValue clear{};
        const VkRenderPassBeginInfo pass_begin{VK_STRUCTURE_TYPE_RENDER_PASS_BEGIN_INFO, nullptr, pass, target.framebuffer,
                                               {{0, 0}, {kWidth, kHeight}}, 1, &clear};
        vkCmdBeginRenderPass(cmd, &pass_begin, VK_SUBPASS_CONTENTS_INLINE);
        vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, pipeline);
        vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, layout, 0, 1, &set, 0, nullptr);
        const auto draw = [&](const View& view, std::uint32_t what, std::uint32_t count, const std::array<float, 4>& rgba) {
            const VkViewport viewport{static_cast<float>(view.x0), 0.0f, kWidth / 2.0f, static_cast<float>(kHeight), 0.0f, 1.0f};
            const VkRect2D scissor{{static_cast<std::int32_t>(view.x0), 0}, {kWidth / 2, kHeight}};
            vkCmdSetViewport(cmd, 0, 1, &viewport);
            vkCmdSetScissor(cmd, 0, 1, &scissor);
            Push push{view.view_proj, {what, kJoints, first_bird, 0}, {rgba[0], rgba[1], rgba[2], rgba[3]}};
            vkCmdPushConstants(cmd, layout, VK_SHADER_STAGE_VERTEX_BIT, 0, sizeof(Push), &push);
            vkCmdDraw(cmd, count, 1, 0, 0);
        };
        draw(chain_view, 0, motion.count, {1.0f, 0.0f, 0.0f, 1.0f});
        draw(bird_view, 1, kBirds, {0.0f, 1.0f, 0.0f, 1.0f});
        vkCmdEndRenderPass(cmd);
        const VkBufferImageCopy region{0, 0, 0, {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1}, {0, 0, 0}, {kWidth, kHeight, 1}};
        vkCmdCopyImageToBuffer(cmd, target.image, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, target.pixels.buffer, 1, &region);
        const VkMemoryBarrier to_host{VK_STRUCTURE_TYPE_MEMORY_BARRIER, nullptr, VK_ACCESS_TRANSFER_WRITE_BIT, VK_ACCESS_HOST_READ_BIT};
        vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_PIPELINE_STAGE_HOST_BIT, 0, 1, &to_host, 0, nullptr, 0, nullptr);
        check(vkEndCommandBuffer(cmd), "vkEndCommandBuffer");
        const VkSubmitInfo submit{VK_STRUCTURE_TYPE_SUBMIT_INFO, nullptr, 0, nullptr, nullptr, 1, &cmd, 0, nullptr};
        check(vkQueueSubmit(app.queue, 1, &submit, fences[slot]), "vkQueueSubmit");
    }
    check(vkWaitForFences(app.device, kFramesInFlight, fences.data(), VK_TRUE, UINT64_MAX), "vkWaitForFences");

    // --- The checks: the drawn points against a read-back of the same state -------------
    ok_or_fail(rods->read(snapshot), "rods read");
    // The flock stepped frame after frame with the same hawk from host arrays: recorded
    // frames are the stepped ones bit for bit, the hawk written on the device too (the
    // module's tests check that), so its last frame is where the drawn birds must be (both
    // ran frames 0 to frames - 1).
    std::unique_ptr<kodawari::Simulation> stepped = open_flock();
    std::vector<kodawari::gpu::BirdPose> expected(kBirds);
    for (std::uint32_t k = 1; k <= frames; ++k) {
        const kodawari::FlockAgent hawk = hawk_at(k, route_start);
        ok_or_fail(kodawari::set_flock_agents(*stepped, std::span(&hawk, 1)), "set_flock_agents");
        ok_or_fail(kodawari::step_birds(*stepped, 1, k == frames ? std::span(expected) : std::span<kodawari::gpu::BirdPose>{}),
                   "the stepped flock");
    }
    std::vector<glm::vec3> bird_points;
    for (std::uint32_t b = 0; b < kBirds; ++b) {
        const kodawari::gpu::vec4& p = expected[b].position;
        bird_points.push_back({p.x, p.y, p.z});
    }
    const auto* rgba = static_cast<const std::uint8_t*>(targets[frames % kFramesInFlight].pixels.mapped);
    const Match chains = match(chain_view, snapshot.positions, rgba, 0);
    const Match flock_match = match(bird_view, bird_points, rgba, 1);
    std::printf("frames %u (%u in flight) on %s, recorded into the application's command buffers\n", frames, kFramesInFlight,
                rods->device().c_str());
    std::printf("chains: %u joints, %u in view, %u drawn where read back, %u lit pixels\n", static_cast<std::uint32_t>(snapshot.positions.size()),
                chains.inside, chains.found, chains.lit);
    std::printf("birds:  %u flocking birds and the application's hawk, %u in view, %u drawn where the stepped flock has them, "
                "%u lit pixels\n",
                kBirds, flock_match.inside, flock_match.found, flock_match.lit);
    std::printf("validation messages: %u%s\n", validation_messages, validation ? "" : " (validation off)");
    if (image_out != nullptr) {
        if (FILE* f = std::fopen(image_out, "wb"); f != nullptr) {
            std::fprintf(f, "P6\n%u %u\n255\n", kWidth, kHeight);
            for (std::size_t i = 0; i < std::size_t{kWidth} * kHeight; ++i) std::fwrite(rgba + i * 4, 1, 3, f);
            std::fclose(f);
        }
    }

    // Every point in view must be drawn where the read-back puts it (within a pixel), and
    // no more pixels lit than there are points: a wrong offset, stride or missing barrier
    // draws them elsewhere or not at all.
    bool passed = true;
    const auto expect = [&](bool condition, const char* what) {
        if (!condition) {
            std::fprintf(stderr, "embed_vulkan: FAILED: %s\n", what);
            passed = false;
        }
    };
    expect(chains.inside >= snapshot.positions.size() * 9 / 10, "at least 90% of the joints in view");
    expect(chains.found == chains.inside, "every joint in view drawn where it was read back");
    expect(chains.lit <= snapshot.positions.size(), "no more chain pixels than joints");
    expect(flock_match.inside >= kBirds * 9 / 10, "at least 90% of the birds in view");
    expect(flock_match.found == flock_match.inside, "every bird in view drawn where the stepped flock has it");
    expect(flock_match.lit <= kBirds, "no more bird pixels than birds");
    expect(validation_messages == 0, "no validation message");

    // --- Teardown: the module first (it destroys only its own objects), then ours ---------
    // (every owner of the device wrapper: the backends and the options that named it).
    stepped.reset();
    flock.reset();
    rods.reset();
    options.context.reset();
    device.reset();
    vkDestroyCommandPool(app.device, cmd_pool, nullptr);
    for (VkFence f : fences) vkDestroyFence(app.device, f, nullptr);
    for (Target& t : targets) {
        vkDestroyFramebuffer(app.device, t.framebuffer, nullptr);
        vkDestroyImageView(app.device, t.view, nullptr);
        vkDestroyImage(app.device, t.image, nullptr);
        vkFreeMemory(app.device, t.memory, nullptr);
        vkDestroyBuffer(app.device, t.pixels.buffer, nullptr);
        vkFreeMemory(app.device, t.pixels.memory, nullptr);
    }
    vkDestroyDescriptorPool(app.device, descriptor_pool, nullptr);
    vkDestroyPipeline(app.device, pipeline, nullptr);
    vkDestroyShaderModule(app.device, vert, nullptr);
    vkDestroyShaderModule(app.device, frag, nullptr);
    vkDestroyPipelineLayout(app.device, layout, nullptr);
    vkDestroyDescriptorSetLayout(app.device, set_layout, nullptr);
    vkDestroyRenderPass(app.device, pass, nullptr);
    // Still the application's, still valid: the module destroyed neither.
    vkDestroyDevice(app.device, nullptr);
    if (app.messenger != VK_NULL_HANDLE) {
        auto destroy = reinterpret_cast<PFN_vkDestroyDebugUtilsMessengerEXT>(vkGetInstanceProcAddr(app.instance, "vkDestroyDebugUtilsMessengerEXT"));
        destroy(app.instance, app.messenger, nullptr);
    }
    vkDestroyInstance(app.instance, nullptr);
    if (validation_messages != 0) passed = false;
    std::printf("%s\n", passed ? "embed_vulkan: passed" : "embed_vulkan: FAILED");
    return passed ? 0 : 1;
}
