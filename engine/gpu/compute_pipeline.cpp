#include "gpu/compute_pipeline.hpp"

namespace kodawari::gpu {

Result<ComputePipeline> ComputePipeline::create(const VulkanContext& ctx, std::string_view shader,
                                                std::span<const vk::DescriptorType> types, std::uint32_t push_bytes,
                                                std::span<const std::uint32_t> specialization) {
    const auto bindings = static_cast<std::uint32_t>(types.size());
    const auto code = embedded_shader(shader);
    assert(!code.empty() && "shader not embedded: add it to shaders/CMakeLists.txt");
    ComputePipeline out;
    out.types_.assign(types.begin(), types.end());
    try {
        const auto& device = ctx.device();
        std::vector<vk::DescriptorSetLayoutBinding> slots(bindings);
        for (std::uint32_t i = 0; i < bindings; ++i) {
            slots[i] = vk::DescriptorSetLayoutBinding{.binding = i,
                        .descriptorType = types[i],
                        .descriptorCount = 1,
                        .stageFlags = vk::ShaderStageFlagBits::eCompute};
        }
        out.set_layout_ = device.createDescriptorSetLayout({.bindingCount = bindings, .pBindings = slots.data()});
        const vk::PushConstantRange push{.stageFlags = vk::ShaderStageFlagBits::eCompute, .offset = 0, .size = push_bytes};
        const vk::DescriptorSetLayout set_layout = *out.set_layout_;
        out.layout_ = device.createPipelineLayout({.setLayoutCount = 1,
                                                   .pSetLayouts = &set_layout,
                                                   .pushConstantRangeCount = push_bytes > 0 ? 1u : 0u,
                                                   .pPushConstantRanges = &push});
        out.module_ = device.createShaderModule({.codeSize = code.size_bytes(), .pCode = code.data()});
        std::vector<vk::SpecializationMapEntry> entries;
        for (std::uint32_t i = 0; i < specialization.size(); ++i) {
            entries.push_back({.constantID = i, .offset = i * 4u, .size = 4});
        }
        const vk::SpecializationInfo spec{.mapEntryCount = static_cast<std::uint32_t>(entries.size()),
                                          .pMapEntries = entries.data(),
                                          .dataSize = specialization.size_bytes(),
                                          .pData = specialization.data()};
        out.pipeline_ = device.createComputePipeline(
            nullptr, {.stage = {.stage = vk::ShaderStageFlagBits::eCompute,
                                .module = *out.module_,
                                .pName = "main",
                                .pSpecializationInfo = specialization.empty() ? nullptr : &spec},
                      .layout = *out.layout_});
        std::vector<vk::DescriptorPoolSize> sizes;
        for (const vk::DescriptorType type : types) sizes.push_back({.type = type, .descriptorCount = 1});
        out.pool_ = device.createDescriptorPool({.flags = vk::DescriptorPoolCreateFlagBits::eFreeDescriptorSet,
                                                 .maxSets = 1,
                                                 .poolSizeCount = static_cast<std::uint32_t>(sizes.size()),
                                                 .pPoolSizes = sizes.data()});
        out.set_ = std::move(device.allocateDescriptorSets(
            {.descriptorPool = *out.pool_, .descriptorSetCount = 1, .pSetLayouts = &set_layout})[0]);
    } catch (const std::exception& e) {
        return vulkan_error("Vulkan pipeline " + std::string(shader), e);
    }
    return out;
}

void ComputePipeline::bind_buffers(const VulkanContext& ctx, std::span<const GpuBuffer* const> buffers) const {
    std::vector<vk::Buffer> handles(buffers.size());
    for (std::size_t i = 0; i < buffers.size(); ++i) handles[i] = buffers[i]->handle();
    bind_buffers(ctx, std::span<const vk::Buffer>(handles));
}

void ComputePipeline::bind_buffers(const VulkanContext& ctx, std::span<const vk::Buffer> buffers) const {
    assert(buffers.size() == types_.size());
    std::vector<vk::DescriptorBufferInfo> infos(buffers.size());
    std::vector<vk::WriteDescriptorSet> writes(buffers.size());
    for (std::uint32_t i = 0; i < buffers.size(); ++i) {
        infos[i] = vk::DescriptorBufferInfo{.buffer = buffers[i], .offset = 0, .range = VK_WHOLE_SIZE};
        writes[i] = vk::WriteDescriptorSet{.dstSet = *set_,
                     .dstBinding = i,
                     .descriptorCount = 1,
                     .descriptorType = types_[i],
                     .pBufferInfo = &infos[i]};
    }
    ctx.device().updateDescriptorSets(writes, {});
}

void ComputePipeline::dispatch(const vk::raii::CommandBuffer& cmd, std::span<const std::byte> push,
                               std::uint32_t groups_x) const {
    cmd.bindPipeline(vk::PipelineBindPoint::eCompute, *pipeline_);
    cmd.bindDescriptorSets(vk::PipelineBindPoint::eCompute, *layout_, 0, *set_, {});
    if (!push.empty()) {
        cmd.pushConstants<std::byte>(*layout_, vk::ShaderStageFlagBits::eCompute, 0, push);
    }
    cmd.dispatch(groups_x, 1, 1);
}

void ComputePipeline::dispatch_for_host(const VulkanContext& ctx, const vk::raii::CommandBuffer& cmd,
                                        std::span<const std::byte> push, std::uint32_t groups_x) const {
    const vk::MemoryBarrier before{.srcAccessMask = vk::AccessFlagBits::eShaderWrite | vk::AccessFlagBits::eTransferWrite,
                                   .dstAccessMask = vk::AccessFlagBits::eShaderRead | vk::AccessFlagBits::eShaderWrite};
    cmd.pipelineBarrier(vk::PipelineStageFlagBits::eComputeShader | vk::PipelineStageFlagBits::eTransfer,
                        vk::PipelineStageFlagBits::eComputeShader, {}, before, {}, {});
    ctx.write_timestamp(cmd, 0, vk::PipelineStageFlagBits::eTopOfPipe);
    dispatch(cmd, push, groups_x);
    ctx.write_timestamp(cmd, 1, vk::PipelineStageFlagBits::eBottomOfPipe);
    const vk::MemoryBarrier after{.srcAccessMask = vk::AccessFlagBits::eShaderWrite,
                                  .dstAccessMask = vk::AccessFlagBits::eHostRead | vk::AccessFlagBits::eTransferRead};
    cmd.pipelineBarrier(vk::PipelineStageFlagBits::eComputeShader,
                        vk::PipelineStageFlagBits::eHost | vk::PipelineStageFlagBits::eTransfer, {}, after, {}, {});
}

}  // namespace kodawari::gpu
