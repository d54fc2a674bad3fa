#pragma once
// Storage buffers: mapped device memory where memory is unified, otherwise
// device-local memory filled and read through host-visible staging buffers.

#include <cstddef>
#include <span>
#include <string>
#include <vector>

#include "gpu/vulkan_context.hpp"

namespace kodawari::gpu {

/// A range of a buffer bound to a storage binding (a GpuBuffer's, or another owner's).
struct BufferRange {
    vk::Buffer buffer;
    vk::DeviceSize offset = 0;
    vk::DeviceSize size = VK_WHOLE_SIZE;
};

class GpuBuffer {
public:
    enum class Kind {
        Storage,   ///< read/written by kernels (storage or uniform); mapped when memory is unified
        Upload,    ///< host-visible source of copies
        Readback,  ///< host-visible (cached when possible) destination of copies
        Vertex,    ///< host-visible, coherent and mapped vertex (or index) buffer written by the CPU
    };

    [[nodiscard]] static Result<GpuBuffer> create(const VulkanContext& ctx, vk::DeviceSize size, Kind kind);

    GpuBuffer(GpuBuffer&&) noexcept = default;
    GpuBuffer& operator=(GpuBuffer&&) noexcept = default;
    GpuBuffer(const GpuBuffer&) = delete;
    GpuBuffer& operator=(const GpuBuffer&) = delete;
    ~GpuBuffer() = default;  // freeing the memory unmaps it

    [[nodiscard]] vk::Buffer handle() const { return *buffer_; }
    [[nodiscard]] vk::DeviceSize size() const { return size_; }
    /// Host address when the memory is mapped, else nullptr.
    [[nodiscard]] std::byte* mapped() const { return mapped_; }
    /// Makes device writes visible to the host (no-op on coherent memory).
    [[nodiscard]] Result<void> invalidate(const VulkanContext& ctx) const;

private:
    GpuBuffer() = default;
    vk::raii::DeviceMemory memory_{nullptr};
    vk::raii::Buffer buffer_{nullptr};
    vk::DeviceSize size_ = 0;
    std::byte* mapped_ = nullptr;
    bool coherent_ = true;
};

/// One Storage buffer per entry of `sizes` (bytes; at least 16 each, so that an empty
/// array still has a buffer to bind). A size over the device's storage-buffer range is an
/// Unsupported error: "<what> needs a storage buffer of N bytes (binding b); <device>
/// allows M".
[[nodiscard]] Result<std::vector<GpuBuffer>> create_storage_buffers(const VulkanContext& ctx,
                                                                    std::span<const std::uint64_t> sizes,
                                                                    const std::string& what);

/// Writes `bytes` into a Storage buffer: by memcpy when mapped, else through a
/// temporary staging buffer and a copy on the queue.
[[nodiscard]] Result<void> upload(VulkanContext& ctx, const GpuBuffer& buffer, std::span<const std::byte> bytes);

/// Reads the first bytes.size() bytes of a Storage buffer that kernels wrote in earlier,
/// completed submissions: by memcpy when mapped, else through a readback buffer.
[[nodiscard]] Result<void> download(VulkanContext& ctx, const GpuBuffer& buffer, std::span<std::byte> bytes);

}  // namespace kodawari::gpu
