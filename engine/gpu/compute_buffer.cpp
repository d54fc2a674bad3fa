// compute::Buffer on Vulkan (kodawari/vulkan/compute.hpp): device memory mapped where memory is
// unified, otherwise device-local memory filled and read through host-visible staging.
#include "gpu/compute_vulkan.hpp"

#include <algorithm>

namespace kodawari::compute {

Device::~Device() = default;

Result<std::vector<KernelStatistics>> Device::kernel_statistics() const {
    return make_error(Error::Kind::Unsupported, "kernel statistics: this device does not capture them");
}

Buffer::Buffer() : native_(std::make_unique<Native>()) {}
Buffer::Buffer(Buffer&&) noexcept = default;
Buffer& Buffer::operator=(Buffer&&) noexcept = default;
// Unmaps (freeing the memory does) after the buffer is destroyed: Native's members in
// reverse order.
Buffer::~Buffer() = default;

Result<Buffer> Buffer::create(const Device& compute_device, std::uint64_t size, Usage usage) {
    const gpu::VulkanContext& device = gpu::vulkan(compute_device);
    Buffer out;
    out.size_ = size;
    out.usage_ = usage;
    using Flag = vk::BufferUsageFlagBits;
    using Memory = vk::MemoryPropertyFlagBits;
    vk::BufferUsageFlags flags;
    vk::MemoryPropertyFlags required, preferred;
    switch (usage) {
        case Usage::Storage:
            flags = Flag::eStorageBuffer | Flag::eUniformBuffer | Flag::eTransferSrc | Flag::eTransferDst;
            required = device.unified_memory() ? Memory::eDeviceLocal | Memory::eHostVisible | Memory::eHostCoherent
                                               : vk::MemoryPropertyFlags(Memory::eDeviceLocal);
            break;
        case Usage::Upload:
            flags = Flag::eTransferSrc;
            required = Memory::eHostVisible | Memory::eHostCoherent;
            break;
        case Usage::Readback:
            flags = Flag::eTransferDst;
            required = Memory::eHostVisible;
            preferred = Memory::eHostCached;
            device.count_readback_buffer(size);
            break;
        case Usage::Vertex:
            // Rewritten by the CPU every frame; device-local too where that exists
            // (unified memory, resizable BAR).
            flags = Flag::eVertexBuffer | Flag::eIndexBuffer;
            required = Memory::eHostVisible | Memory::eHostCoherent;
            preferred = Memory::eDeviceLocal;
            break;
    }
    return guard("Vulkan buffer of " + std::to_string(size) + " bytes", [&]() -> Result<Buffer> {
        out.native_->buffer = device.device().createBuffer({.size = size, .usage = flags, .sharingMode = vk::SharingMode::eExclusive}, device.allocator());
        const auto needs = out.native_->buffer.getMemoryRequirements();
        auto type = device.memory_type(needs.memoryTypeBits, required, preferred);
        if (!type) return type.error();
        out.native_->memory = device.device().allocateMemory({.allocationSize = needs.size, .memoryTypeIndex = type.value()}, device.allocator());
        out.native_->buffer.bindMemory(*out.native_->memory, 0);
        const auto properties = device.physical_device().getMemoryProperties().memoryTypes[type.value()].propertyFlags;
        if (properties & Memory::eHostVisible) {
            out.mapped_ = static_cast<std::byte*>(out.native_->memory.mapMemory(0, VK_WHOLE_SIZE));
            out.coherent_ = static_cast<bool>(properties & Memory::eHostCoherent);
        }
        return std::move(out);
    });
}

Result<void> Buffer::invalidate(const Device& device) const {
    if (coherent_ || mapped_ == nullptr) return {};
    return guard("invalidate", [&]() -> Result<void> {
        gpu::vulkan(device).device().invalidateMappedMemoryRanges(vk::MappedMemoryRange{.memory = *native_->memory, .offset = 0, .size = VK_WHOLE_SIZE});
        return {};
    });
}

Result<std::vector<Buffer>> create_storage_buffers(const Device& device, std::span<const std::uint64_t> sizes,
                                                   const std::string& what) {
    std::vector<Buffer> out;
    out.reserve(sizes.size());
    for (std::size_t b = 0; b < sizes.size(); ++b) {
        if (sizes[b] > device.info().max_storage_buffer_range) {
            return make_error(Error::Kind::Unsupported, what + " needs a storage buffer of " + std::to_string(sizes[b]) +
                                                            " bytes (binding " + std::to_string(b) + "); " + device.info().name +
                                                            " allows " + std::to_string(device.info().max_storage_buffer_range));
        }
        auto buffer = Buffer::create(device, std::max<std::uint64_t>(sizes[b], 16), Usage::Storage);
        if (!buffer) return buffer.error();
        out.push_back(std::move(buffer).value());
    }
    return out;
}

}  // namespace kodawari::compute
