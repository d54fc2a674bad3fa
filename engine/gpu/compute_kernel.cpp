// compute::Kernel on Vulkan (kodawari/vulkan/compute.hpp): a compute pipeline, its layout and its
// one descriptor set.
#include "gpu/compute_vulkan.hpp"

#include <algorithm>
#include <cassert>
#include <string>

namespace kodawari::compute {

Result<std::uint32_t> workgroup_size(const Device& device, unsigned requested, std::uint32_t preferred, std::string_view what) {
    const std::uint32_t size = requested == 0 ? preferred : requested;
    const GpuDeviceInfo& info = device.info();
    // A device reports at least 128 for both limits (the Vulkan specification's minimum).
    const std::uint32_t limit = std::min(info.max_workgroup_size_x > 0 ? info.max_workgroup_size_x : 128u,
                                         info.max_workgroup_invocations > 0 ? info.max_workgroup_invocations : 128u);
    if (!is_workgroup_size(size) || size > limit) {
        return make_error(Error::Kind::InvalidInput,
                          std::string(what) + ": " + std::to_string(size) +
                              " invocations per workgroup; expected a power of two from 32 to " +
                              std::to_string(std::min(limit, 1024u)) + " (" + info.name + "'s limit " + std::to_string(limit) + ")");
    }
    return size;
}

Kernel::Kernel() : native_(std::make_unique<Native>()) {}
Kernel::Kernel(Kernel&&) noexcept = default;
Kernel& Kernel::operator=(Kernel&&) noexcept = default;
Kernel::~Kernel() = default;

Result<Kernel> Kernel::create(const Device& device, std::string_view shader, std::span<const Binding> bindings,
                              std::uint32_t push_bytes, std::span<const std::uint32_t> specialization) {
    const auto code = embedded_shader(shader);
    if (code.empty()) {
        return make_error(Error::Kind::InvalidInput, "kernel " + std::string(shader) +
                                                         ": not one of the engine's shaders (shaders/CMakeLists.txt embeds them)");
    }
    return create(device, shader, code, bindings, push_bytes, specialization);
}

namespace {

// A pipeline's statistics (VK_KHR_pipeline_executable_properties), read once it is created
// with VK_PIPELINE_CREATE_CAPTURE_STATISTICS_BIT_KHR. A driver's failure here is noted, not
// fatal: the kernel runs without its statistics.
compute::KernelStatistics statistics_of(const gpu::VulkanContext& device, vk::Pipeline pipeline, std::string_view shader,
                                        std::span<const std::uint32_t> specialization) {
    compute::KernelStatistics out;
    out.kernel = std::string(shader);
    out.specialization.assign(specialization.begin(), specialization.end());
    try {
        const auto& vk_device = device.device();
        const auto executables = vk_device.getPipelineExecutablePropertiesKHR({.pipeline = pipeline});
        for (std::uint32_t e = 0; e < executables.size(); ++e) {
            const std::string executable(executables[e].name.data());
            for (const vk::PipelineExecutableStatisticKHR& s :
                 vk_device.getPipelineExecutableStatisticsKHR({.pipeline = pipeline, .executableIndex = e})) {
                std::string value;
                switch (s.format) {
                case vk::PipelineExecutableStatisticFormatKHR::eBool32: value = s.value.b32 ? "true" : "false"; break;
                case vk::PipelineExecutableStatisticFormatKHR::eInt64: value = std::to_string(s.value.i64); break;
                case vk::PipelineExecutableStatisticFormatKHR::eUint64: value = std::to_string(s.value.u64); break;
                case vk::PipelineExecutableStatisticFormatKHR::eFloat64: value = std::to_string(s.value.f64); break;
                }
                out.values.push_back({executable, std::string(s.name.data()), std::move(value)});
            }
        }
    } catch (const std::exception& e) {
        out.note = std::string("the driver's statistics could not be read: ") + e.what();
    }
    return out;
}

}  // namespace

Result<Kernel> Kernel::create(const Device& compute_device, std::string_view shader, std::span<const std::uint32_t> code,
                              std::span<const Binding> bindings, std::uint32_t push_bytes,
                              std::span<const std::uint32_t> specialization) {
    if (code.empty()) return make_error(Error::Kind::InvalidInput, "kernel " + std::string(shader) + ": no SPIR-V");
    const auto count = static_cast<std::uint32_t>(bindings.size());
    const gpu::VulkanContext& device = gpu::vulkan(compute_device);
    Kernel out;
    Native& n = *out.native_;
    n.device = &device;
    for (const Binding b : bindings) {
        n.types.push_back(b == Binding::Uniform ? vk::DescriptorType::eUniformBuffer : vk::DescriptorType::eStorageBuffer);
    }
    return guard("Vulkan pipeline " + std::string(shader), [&]() -> Result<Kernel> {
        const auto& vk_device = device.device();
        std::vector<vk::DescriptorSetLayoutBinding> slots(count);
        for (std::uint32_t i = 0; i < count; ++i) {
            slots[i] = vk::DescriptorSetLayoutBinding{.binding = i,
                                                      .descriptorType = n.types[i],
                                                      .descriptorCount = 1,
                                                      .stageFlags = vk::ShaderStageFlagBits::eCompute};
        }
        n.set_layout = vk_device.createDescriptorSetLayout({.bindingCount = count, .pBindings = slots.data()}, device.allocator());
        const vk::PushConstantRange push{.stageFlags = vk::ShaderStageFlagBits::eCompute, .offset = 0, .size = push_bytes};
        const vk::DescriptorSetLayout set_layout = *n.set_layout;
        n.layout = vk_device.createPipelineLayout({.setLayoutCount = 1,
                                                      .pSetLayouts = &set_layout,
                                                      .pushConstantRangeCount = push_bytes > 0 ? 1u : 0u,
                                                      .pPushConstantRanges = &push}, device.allocator());
        n.module = vk_device.createShaderModule({.codeSize = code.size_bytes(), .pCode = code.data()}, device.allocator());
        std::vector<vk::SpecializationMapEntry> entries;
        for (std::uint32_t i = 0; i < specialization.size(); ++i) {
            entries.push_back({.constantID = i, .offset = i * 4u, .size = 4});
        }
        const vk::SpecializationInfo spec{.mapEntryCount = static_cast<std::uint32_t>(entries.size()),
                                          .pMapEntries = entries.data(),
                                          .dataSize = specialization.size_bytes(),
                                          .pData = specialization.data()};
        n.pipeline = vk_device.createComputePipeline(
            nullptr, {.flags = device.captures_statistics() ? vk::PipelineCreateFlagBits::eCaptureStatisticsKHR : vk::PipelineCreateFlags{},
                      .stage = {.stage = vk::ShaderStageFlagBits::eCompute,
                                .module = *n.module,
                                .pName = "main",
                                .pSpecializationInfo = specialization.empty() ? nullptr : &spec},
                      .layout = *n.layout}, device.allocator());
        if (device.captures_statistics()) device.add_statistics(statistics_of(device, *n.pipeline, shader, specialization));
        std::vector<vk::DescriptorPoolSize> sizes;
        for (const vk::DescriptorType type : n.types) sizes.push_back({.type = type, .descriptorCount = 1});
        n.pool = vk_device.createDescriptorPool({.flags = vk::DescriptorPoolCreateFlagBits::eFreeDescriptorSet,
                                                    .maxSets = 1,
                                                    .poolSizeCount = static_cast<std::uint32_t>(sizes.size()),
                                                    .pPoolSizes = sizes.data()}, device.allocator());
        n.set = std::move(vk_device.allocateDescriptorSets(
            {.descriptorPool = *n.pool, .descriptorSetCount = 1, .pSetLayouts = &set_layout})[0]);
        return std::move(out);
    });
}

void Kernel::bind(std::span<const Buffer* const> buffers) const {
    std::vector<BufferView> views;
    views.reserve(buffers.size());
    for (const Buffer* b : buffers) views.push_back({b});
    bind(views);
}

void Kernel::bind(std::span<const BufferView> views) const {
    std::vector<gpu::BufferRange> ranges(views.size());
    for (std::size_t i = 0; i < views.size(); ++i) {
        assert(views[i].buffer != nullptr && "a view of a buffer");
        ranges[i] = {gpu::vk_buffer(*views[i].buffer), views[i].offset,
                     views[i].size == kWholeSize ? VK_WHOLE_SIZE : vk::DeviceSize{views[i].size}};
    }
    gpu::bind(*this, ranges);
}

void Kernel::dispatch(Recording& recording, std::span<const std::byte> push, std::uint32_t groups_x) const {
    gpu::dispatch(*this, gpu::vk_commands(recording), push, groups_x);
}

}  // namespace kodawari::compute

namespace kodawari::gpu {

void dispatch(const compute::Kernel& kernel, const vk::raii::CommandBuffer& cmd, std::span<const std::byte> push,
              std::uint32_t groups_x) {
    const compute::Kernel::Native& n = kernel.native();
    cmd.bindPipeline(vk::PipelineBindPoint::eCompute, *n.pipeline);
    cmd.bindDescriptorSets(vk::PipelineBindPoint::eCompute, *n.layout, 0, *n.set, {});
    if (!push.empty()) cmd.pushConstants<std::byte>(*n.layout, vk::ShaderStageFlagBits::eCompute, 0, push);
    cmd.dispatch(groups_x, 1, 1);
}

void bind(const compute::Kernel& kernel, std::span<const BufferRange> ranges) {
    const compute::Kernel::Native& n = kernel.native();
    assert(ranges.size() == n.types.size());
    std::vector<vk::DescriptorBufferInfo> infos(ranges.size());
    std::vector<vk::WriteDescriptorSet> writes(ranges.size());
    for (std::uint32_t i = 0; i < ranges.size(); ++i) {
        infos[i] = vk::DescriptorBufferInfo{.buffer = ranges[i].buffer, .offset = ranges[i].offset, .range = ranges[i].size};
        writes[i] = vk::WriteDescriptorSet{.dstSet = *n.set,
                                           .dstBinding = i,
                                           .descriptorCount = 1,
                                           .descriptorType = n.types[i],
                                           .pBufferInfo = &infos[i]};
    }
    n.device->device().updateDescriptorSets(writes, {});
}

}  // namespace kodawari::gpu
