#include "gpu/graphics.hpp"

#include <cassert>
#include <vector>

#include "gpu/compute_vulkan.hpp"

namespace kodawari::gpu {

Result<GpuImage> GpuImage::create(const VulkanContext& ctx, std::uint32_t width, std::uint32_t height, vk::Format format,
                                  vk::ImageUsageFlags usage, vk::ImageAspectFlags aspect, vk::SampleCountFlagBits samples) {
    GpuImage out;
    KW_TRY(guard("Vulkan image " + std::to_string(width) + "x" + std::to_string(height) + " " + vk::to_string(format), [&]() -> Result<void> {
        const auto& device = ctx.device();
        out.image_ = device.createImage({.imageType = vk::ImageType::e2D,
                                         .format = format,
                                         .extent = {width, height, 1},
                                         .mipLevels = 1,
                                         .arrayLayers = 1,
                                         .samples = samples,
                                         .tiling = vk::ImageTiling::eOptimal,
                                         .usage = usage,
                                         .sharingMode = vk::SharingMode::eExclusive,
                                         .initialLayout = vk::ImageLayout::eUndefined});
        const auto needs = out.image_.getMemoryRequirements();
        auto type = ctx.memory_type(needs.memoryTypeBits, vk::MemoryPropertyFlagBits::eDeviceLocal);
        if (!type) return type.error();
        out.memory_ = device.allocateMemory({.allocationSize = needs.size, .memoryTypeIndex = type.value()});
        out.image_.bindMemory(*out.memory_, 0);
        out.view_ = device.createImageView({.image = *out.image_,
                                            .viewType = vk::ImageViewType::e2D,
                                            .format = format,
                                            .subresourceRange = {.aspectMask = aspect, .levelCount = 1, .layerCount = 1}});
        return {};
    }));
    return out;
}

Result<GraphicsPipeline> GraphicsPipeline::create(const VulkanContext& ctx, vk::RenderPass render_pass, std::string_view vertex,
                                                  std::string_view fragment, std::uint32_t vertex_stride, std::uint32_t attributes,
                                                  std::uint32_t push_bytes, const GraphicsPipelineOptions& options) {
    const auto vertex_code = embedded_shader(vertex);
    const auto fragment_code = embedded_shader(fragment);
    assert(!vertex_code.empty() && !fragment_code.empty() && "shader not embedded: add it to shaders/CMakeLists.txt");
    GraphicsPipeline out;
    KW_TRY(guard("Vulkan graphics pipeline " + std::string(vertex) + " + " + std::string(fragment), [&]() -> Result<void> {
        const auto& device = ctx.device();
        const vk::PushConstantRange push{.stageFlags = vk::ShaderStageFlagBits::eVertex | vk::ShaderStageFlagBits::eFragment,
                                         .offset = 0,
                                         .size = push_bytes};
        std::vector<vk::DescriptorSetLayoutBinding> bindings;
        for (std::uint32_t b = 0; b < options.storage_buffers; ++b) {
            bindings.push_back({.binding = b,
                                .descriptorType = vk::DescriptorType::eStorageBuffer,
                                .descriptorCount = 1,
                                .stageFlags = vk::ShaderStageFlagBits::eVertex});
        }
        out.storage_buffers_ = options.storage_buffers;
        if (!bindings.empty()) {
            out.set_layout_ = device.createDescriptorSetLayout(
                {.bindingCount = static_cast<std::uint32_t>(bindings.size()), .pBindings = bindings.data()});
        }
        const vk::DescriptorSetLayout set_layout = *out.set_layout_;
        out.layout_ = device.createPipelineLayout({.setLayoutCount = bindings.empty() ? 0u : 1u,
                                                   .pSetLayouts = &set_layout,
                                                   .pushConstantRangeCount = push_bytes > 0 ? 1u : 0u,
                                                   .pPushConstantRanges = &push});
        out.vertex_ = device.createShaderModule({.codeSize = vertex_code.size_bytes(), .pCode = vertex_code.data()});
        out.fragment_ = device.createShaderModule({.codeSize = fragment_code.size_bytes(), .pCode = fragment_code.data()});
        const vk::PipelineShaderStageCreateInfo stages[] = {
            {.stage = vk::ShaderStageFlagBits::eVertex, .module = *out.vertex_, .pName = "main"},
            {.stage = vk::ShaderStageFlagBits::eFragment, .module = *out.fragment_, .pName = "main"},
        };
        const vk::VertexInputBindingDescription binding{.binding = 0, .stride = vertex_stride, .inputRate = vk::VertexInputRate::eVertex};
        std::vector<vk::VertexInputAttributeDescription> attribute_list;
        for (std::uint32_t i = 0; i < attributes; ++i) {
            attribute_list.push_back({.location = i, .binding = 0, .format = vk::Format::eR32G32B32A32Sfloat, .offset = 16 * i});
        }
        const vk::PipelineVertexInputStateCreateInfo vertex_input{.vertexBindingDescriptionCount = attributes > 0 ? 1u : 0u,
                                                                   .pVertexBindingDescriptions = &binding,
                                                                   .vertexAttributeDescriptionCount = attributes,
                                                                   .pVertexAttributeDescriptions = attribute_list.data()};
        const vk::PipelineInputAssemblyStateCreateInfo assembly{.topology = options.topology};
        const vk::PipelineViewportStateCreateInfo viewport{.viewportCount = 1, .scissorCount = 1};
        const vk::PipelineRasterizationStateCreateInfo raster{.polygonMode = vk::PolygonMode::eFill,
                                                              .cullMode = vk::CullModeFlagBits::eNone,
                                                              .frontFace = vk::FrontFace::eCounterClockwise,
                                                              .lineWidth = 1.0f};
        const vk::PipelineMultisampleStateCreateInfo multisample{.rasterizationSamples = options.samples};
        const vk::PipelineDepthStencilStateCreateInfo depth{.depthTestEnable = options.depth,
                                                            .depthWriteEnable = options.depth && !options.blend,
                                                            .depthCompareOp = vk::CompareOp::eLess};
        const vk::PipelineColorBlendAttachmentState blend_attachment{
            .blendEnable = options.blend ? VK_TRUE : VK_FALSE,
            .srcColorBlendFactor = vk::BlendFactor::eSrcAlpha,
            .dstColorBlendFactor = vk::BlendFactor::eOneMinusSrcAlpha,
            .colorBlendOp = vk::BlendOp::eAdd,
            .srcAlphaBlendFactor = vk::BlendFactor::eZero,
            .dstAlphaBlendFactor = vk::BlendFactor::eOne,
            .alphaBlendOp = vk::BlendOp::eAdd,
            .colorWriteMask = vk::ColorComponentFlagBits::eR | vk::ColorComponentFlagBits::eG | vk::ColorComponentFlagBits::eB |
                              vk::ColorComponentFlagBits::eA};
        const vk::PipelineColorBlendStateCreateInfo blend{.attachmentCount = 1, .pAttachments = &blend_attachment};
        const vk::DynamicState dynamic_states[] = {vk::DynamicState::eViewport, vk::DynamicState::eScissor};
        const vk::PipelineDynamicStateCreateInfo dynamic{.dynamicStateCount = 2, .pDynamicStates = dynamic_states};
        out.pipeline_ = device.createGraphicsPipeline(nullptr, {.stageCount = 2,
                                                                .pStages = stages,
                                                                .pVertexInputState = &vertex_input,
                                                                .pInputAssemblyState = &assembly,
                                                                .pViewportState = &viewport,
                                                                .pRasterizationState = &raster,
                                                                .pMultisampleState = &multisample,
                                                                .pDepthStencilState = &depth,
                                                                .pColorBlendState = &blend,
                                                                .pDynamicState = &dynamic,
                                                                .layout = *out.layout_,
                                                                .renderPass = render_pass,
                                                                .subpass = 0});
        return {};
    }));
    return out;
}

Result<BufferSet> BufferSet::create(const VulkanContext& ctx, const GraphicsPipeline& pipeline) {
    assert(pipeline.storage_buffers() > 0 && "the pipeline has no storage buffers");
    BufferSet out;
    out.count_ = pipeline.storage_buffers();
    KW_TRY(guard("Vulkan descriptor set", [&]() -> Result<void> {
        const vk::DescriptorPoolSize size{.type = vk::DescriptorType::eStorageBuffer, .descriptorCount = out.count_};
        out.pool_ = ctx.device().createDescriptorPool(
            {.flags = vk::DescriptorPoolCreateFlagBits::eFreeDescriptorSet, .maxSets = 1, .poolSizeCount = 1, .pPoolSizes = &size});
        const vk::DescriptorSetLayout layout = pipeline.set_layout();
        out.set_ = std::move(ctx.device().allocateDescriptorSets({.descriptorPool = *out.pool_, .descriptorSetCount = 1, .pSetLayouts = &layout})[0]);
        return {};
    }));
    return out;
}

void BufferSet::bind(const VulkanContext& ctx, std::span<const BufferRange> buffers) {
    assert(buffers.size() == count_ && "one buffer per binding");
    std::vector<vk::DescriptorBufferInfo> infos;
    std::vector<vk::WriteDescriptorSet> writes;
    infos.reserve(buffers.size());
    for (const BufferRange& b : buffers) infos.push_back({.buffer = b.buffer, .offset = b.offset, .range = b.size});
    for (std::uint32_t i = 0; i < count_; ++i) {
        writes.push_back({.dstSet = *set_,
                          .dstBinding = i,
                          .descriptorCount = 1,
                          .descriptorType = vk::DescriptorType::eStorageBuffer,
                          .pBufferInfo = &infos[i]});
    }
    ctx.device().updateDescriptorSets(writes, {});
}

}  // namespace kodawari::gpu
