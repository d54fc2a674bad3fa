#include "compute/kernel.hpp"

#include <cassert>
#include <string>

namespace kodawari::compute {

Result<Kernel> Kernel::create(const Device& device, std::string_view shader, std::span<const Binding> bindings,
                              std::uint32_t push_bytes, std::span<const std::uint32_t> specialization) {
    const auto code = embedded_shader(shader);
    assert(!code.empty() && "shader not embedded: add it to shaders/CMakeLists.txt");
    return create(device, shader, code, bindings, push_bytes, specialization);
}

Result<Kernel> Kernel::create(const Device& device, std::string_view shader, std::span<const std::uint32_t> code,
                              std::span<const Binding> bindings, std::uint32_t push_bytes,
                              std::span<const std::uint32_t> specialization) {
    if (code.empty()) return make_error(Error::Kind::InvalidInput, "kernel " + std::string(shader) + ": no SPIR-V");
    const auto count = static_cast<std::uint32_t>(bindings.size());
    Kernel out;
    out.device_ = &device;
    for (const Binding b : bindings) {
        out.types_.push_back(b == Binding::Uniform ? vk::DescriptorType::eUniformBuffer : vk::DescriptorType::eStorageBuffer);
    }
    return guard("Vulkan pipeline " + std::string(shader), [&]() -> Result<Kernel> {
        const auto& vk_device = device.device();
        std::vector<vk::DescriptorSetLayoutBinding> slots(count);
        for (std::uint32_t i = 0; i < count; ++i) {
            slots[i] = vk::DescriptorSetLayoutBinding{.binding = i,
                                                      .descriptorType = out.types_[i],
                                                      .descriptorCount = 1,
                                                      .stageFlags = vk::ShaderStageFlagBits::eCompute};
        }
        out.set_layout_ = vk_device.createDescriptorSetLayout({.bindingCount = count, .pBindings = slots.data()}, device.allocator());
        const vk::PushConstantRange push{.stageFlags = vk::ShaderStageFlagBits::eCompute, .offset = 0, .size = push_bytes};
        const vk::DescriptorSetLayout set_layout = *out.set_layout_;
        out.layout_ = vk_device.createPipelineLayout({.setLayoutCount = 1,
                                                      .pSetLayouts = &set_layout,
                                                      .pushConstantRangeCount = push_bytes > 0 ? 1u : 0u,
                                                      .pPushConstantRanges = &push}, device.allocator());
        out.module_ = vk_device.createShaderModule({.codeSize = code.size_bytes(), .pCode = code.data()}, device.allocator());
        std::vector<vk::SpecializationMapEntry> entries;
        for (std::uint32_t i = 0; i < specialization.size(); ++i) {
            entries.push_back({.constantID = i, .offset = i * 4u, .size = 4});
        }
        const vk::SpecializationInfo spec{.mapEntryCount = static_cast<std::uint32_t>(entries.size()),
                                          .pMapEntries = entries.data(),
                                          .dataSize = specialization.size_bytes(),
                                          .pData = specialization.data()};
        out.pipeline_ = vk_device.createComputePipeline(
            nullptr, {.stage = {.stage = vk::ShaderStageFlagBits::eCompute,
                                .module = *out.module_,
                                .pName = "main",
                                .pSpecializationInfo = specialization.empty() ? nullptr : &spec},
                      .layout = *out.layout_}, device.allocator());
        std::vector<vk::DescriptorPoolSize> sizes;
        for (const vk::DescriptorType type : out.types_) sizes.push_back({.type = type, .descriptorCount = 1});
        out.pool_ = vk_device.createDescriptorPool({.flags = vk::DescriptorPoolCreateFlagBits::eFreeDescriptorSet,
                                                    .maxSets = 1,
                                                    .poolSizeCount = static_cast<std::uint32_t>(sizes.size()),
                                                    .pPoolSizes = sizes.data()}, device.allocator());
        out.set_ = std::move(vk_device.allocateDescriptorSets(
            {.descriptorPool = *out.pool_, .descriptorSetCount = 1, .pSetLayouts = &set_layout})[0]);
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
    assert(views.size() == types_.size());
    std::vector<vk::DescriptorBufferInfo> infos(views.size());
    std::vector<vk::WriteDescriptorSet> writes(views.size());
    for (std::uint32_t i = 0; i < views.size(); ++i) {
        const vk::Buffer buffer = views[i].buffer != nullptr ? views[i].buffer->handle() : views[i].foreign;
        infos[i] = vk::DescriptorBufferInfo{.buffer = buffer, .offset = views[i].offset, .range = views[i].size};
        writes[i] = vk::WriteDescriptorSet{.dstSet = *set_,
                                           .dstBinding = i,
                                           .descriptorCount = 1,
                                           .descriptorType = types_[i],
                                           .pBufferInfo = &infos[i]};
    }
    device_->device().updateDescriptorSets(writes, {});
}

void Kernel::dispatch(Recording& recording, std::span<const std::byte> push, std::uint32_t groups_x) const {
    dispatch(recording.vulkan(), push, groups_x);
}

void Kernel::dispatch(const vk::raii::CommandBuffer& cmd, std::span<const std::byte> push, std::uint32_t groups_x) const {
    cmd.bindPipeline(vk::PipelineBindPoint::eCompute, *pipeline_);
    cmd.bindDescriptorSets(vk::PipelineBindPoint::eCompute, *layout_, 0, *set_, {});
    if (!push.empty()) cmd.pushConstants<std::byte>(*layout_, vk::ShaderStageFlagBits::eCompute, 0, push);
    cmd.dispatch(groups_x, 1, 1);
}

}  // namespace kodawari::compute
