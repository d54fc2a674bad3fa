#include "gpu/gpu_buffer.hpp"

#include <algorithm>
#include <cassert>
#include <cstring>

namespace kodawari::gpu {

Result<GpuBuffer> GpuBuffer::create(const VulkanContext& ctx, vk::DeviceSize size, Kind kind) {
    GpuBuffer out;
    out.size_ = size;
    using Usage = vk::BufferUsageFlagBits;
    using Memory = vk::MemoryPropertyFlagBits;
    vk::BufferUsageFlags usage;
    vk::MemoryPropertyFlags required, preferred;
    switch (kind) {
        case Kind::Storage:
            usage = Usage::eStorageBuffer | Usage::eUniformBuffer | Usage::eTransferSrc | Usage::eTransferDst;
            required = ctx.unified_memory() ? Memory::eDeviceLocal | Memory::eHostVisible | Memory::eHostCoherent
                                            : vk::MemoryPropertyFlags(Memory::eDeviceLocal);
            break;
        case Kind::Upload:
            usage = Usage::eTransferSrc;
            required = Memory::eHostVisible | Memory::eHostCoherent;
            break;
        case Kind::Readback:
            usage = Usage::eTransferDst;
            required = Memory::eHostVisible;
            preferred = Memory::eHostCached;
            break;
        case Kind::Vertex:
            // Rewritten by the CPU every frame; device-local too where that exists
            // (unified memory, resizable BAR).
            usage = Usage::eVertexBuffer | Usage::eIndexBuffer;
            required = Memory::eHostVisible | Memory::eHostCoherent;
            preferred = Memory::eDeviceLocal;
            break;
    }
    try {
        out.buffer_ = ctx.device().createBuffer({.size = size, .usage = usage, .sharingMode = vk::SharingMode::eExclusive});
        const auto needs = out.buffer_.getMemoryRequirements();
        auto type = ctx.memory_type(needs.memoryTypeBits, required, preferred);
        if (!type) return type.error();
        out.memory_ = ctx.device().allocateMemory({.allocationSize = needs.size, .memoryTypeIndex = type.value()});
        out.buffer_.bindMemory(*out.memory_, 0);
        const auto flags = ctx.physical_device().getMemoryProperties().memoryTypes[type.value()].propertyFlags;
        if (flags & Memory::eHostVisible) {
            out.mapped_ = static_cast<std::byte*>(out.memory_.mapMemory(0, VK_WHOLE_SIZE));
            out.coherent_ = static_cast<bool>(flags & Memory::eHostCoherent);
        }
    } catch (const std::exception& e) {
        return vulkan_error("Vulkan buffer of " + std::to_string(size) + " bytes", e);
    }
    return out;
}

Result<void> GpuBuffer::invalidate(const VulkanContext& ctx) const {
    if (coherent_ || mapped_ == nullptr) return {};
    try {
        ctx.device().invalidateMappedMemoryRanges(vk::MappedMemoryRange{.memory = *memory_, .offset = 0, .size = VK_WHOLE_SIZE});
    } catch (const std::exception& e) {
        return vulkan_error("invalidate", e);
    }
    return {};
}

Result<void> upload(VulkanContext& ctx, const GpuBuffer& buffer, std::span<const std::byte> bytes) {
    assert(bytes.size() <= buffer.size());
    if (bytes.empty()) return {};
    if (buffer.mapped() != nullptr) {
        std::memcpy(buffer.mapped(), bytes.data(), bytes.size());
        return {};
    }
    auto staging = GpuBuffer::create(ctx, bytes.size(), GpuBuffer::Kind::Upload);
    if (!staging) return staging.error();
    std::memcpy(staging.value().mapped(), bytes.data(), bytes.size());
    return ctx.submit([&](const vk::raii::CommandBuffer& cmd) {
        cmd.copyBuffer(staging.value().handle(), buffer.handle(), vk::BufferCopy{.size = bytes.size()});
        // The kernels read what the copy wrote.
        const vk::MemoryBarrier barrier{.srcAccessMask = vk::AccessFlagBits::eTransferWrite,
                                        .dstAccessMask = vk::AccessFlagBits::eShaderRead | vk::AccessFlagBits::eShaderWrite};
        cmd.pipelineBarrier(vk::PipelineStageFlagBits::eTransfer, vk::PipelineStageFlagBits::eComputeShader, {}, barrier, {}, {});
    });
}

}  // namespace kodawari::gpu

namespace kodawari::gpu {

Result<void> download(VulkanContext& ctx, const GpuBuffer& buffer, std::span<std::byte> bytes) {
    assert(bytes.size() <= buffer.size());
    if (bytes.empty()) return {};
    ctx.count_read_back(bytes.size());
    if (buffer.mapped() != nullptr) {
        KW_TRY(buffer.invalidate(ctx));
        std::memcpy(bytes.data(), buffer.mapped(), bytes.size());
        return {};
    }
    auto staging = GpuBuffer::create(ctx, bytes.size(), GpuBuffer::Kind::Readback);
    if (!staging) return staging.error();
    KW_TRY(ctx.submit([&](const vk::raii::CommandBuffer& cmd) {
        // The kernels wrote what the copy reads; the host then reads the copy.
        const vk::MemoryBarrier before{.srcAccessMask = vk::AccessFlagBits::eShaderWrite,
                                       .dstAccessMask = vk::AccessFlagBits::eTransferRead};
        cmd.pipelineBarrier(vk::PipelineStageFlagBits::eComputeShader, vk::PipelineStageFlagBits::eTransfer, {}, before, {}, {});
        cmd.copyBuffer(buffer.handle(), staging.value().handle(), vk::BufferCopy{.size = bytes.size()});
        const vk::MemoryBarrier after{.srcAccessMask = vk::AccessFlagBits::eTransferWrite,
                                      .dstAccessMask = vk::AccessFlagBits::eHostRead};
        cmd.pipelineBarrier(vk::PipelineStageFlagBits::eTransfer, vk::PipelineStageFlagBits::eHost, {}, after, {}, {});
    }));
    KW_TRY(staging.value().invalidate(ctx));
    std::memcpy(bytes.data(), staging.value().mapped(), bytes.size());
    return {};
}

Result<std::vector<GpuBuffer>> create_storage_buffers(const VulkanContext& ctx, std::span<const std::uint64_t> sizes,
                                                      const std::string& what) {
    std::vector<GpuBuffer> out;
    out.reserve(sizes.size());
    for (std::size_t b = 0; b < sizes.size(); ++b) {
        if (sizes[b] > ctx.info().max_storage_buffer_range) {
            return make_error(Error::Kind::Unsupported, what + " needs a storage buffer of " + std::to_string(sizes[b]) +
                                                            " bytes (binding " + std::to_string(b) + "); " + ctx.info().name +
                                                            " allows " + std::to_string(ctx.info().max_storage_buffer_range));
        }
        auto buffer = GpuBuffer::create(ctx, std::max<std::uint64_t>(sizes[b], 16), GpuBuffer::Kind::Storage);
        if (!buffer) return buffer.error();
        out.push_back(std::move(buffer).value());
    }
    return out;
}

}  // namespace kodawari::gpu
