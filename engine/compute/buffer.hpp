#pragma once
// Typed device buffers of the compute layer: mapped device memory where memory is unified,
// otherwise device-local memory filled and read through host-visible staging buffers.

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "compute/device.hpp"
#include "core/internal_api.hpp"

namespace kodawari::compute {

/// What a buffer is for; decides its memory (see Buffer::create).
enum class Usage {
    Storage,   ///< read/written by kernels (storage or uniform); mapped when memory is unified
    Upload,    ///< host-visible source of copies
    Readback,  ///< host-visible (cached when possible) destination of copies
    Vertex,    ///< host-visible, coherent and mapped vertex (or index) buffer written by the CPU
};

/// A buffer and its memory, owned (move-only; freeing the memory unmaps it).
class KODAWARI_INTERNAL Buffer {
public:
    using Kind = Usage;  // the renderer's older name

    [[nodiscard]] static Result<Buffer> create(const Device& device, std::uint64_t size, Usage usage);

    Buffer(Buffer&&) noexcept = default;
    Buffer& operator=(Buffer&&) noexcept = default;
    Buffer(const Buffer&) = delete;
    Buffer& operator=(const Buffer&) = delete;
    ~Buffer() = default;

    [[nodiscard]] std::uint64_t size() const { return size_; }
    [[nodiscard]] Usage usage() const { return usage_; }
    /// Host address when the memory is mapped, else nullptr.
    [[nodiscard]] std::byte* mapped() const { return mapped_; }
    /// Makes device writes visible to the host (no-op on coherent memory).
    [[nodiscard]] Result<void> invalidate(const Device& device) const;

    /// The Vulkan buffer (the implementation's; for the renderer's descriptor sets and copies).
    [[nodiscard]] vk::Buffer handle() const { return *buffer_; }

private:
    Buffer() = default;
    vk::raii::DeviceMemory memory_{nullptr};
    vk::raii::Buffer buffer_{nullptr};
    std::uint64_t size_ = 0;
    std::byte* mapped_ = nullptr;
    Usage usage_ = Usage::Storage;
    bool coherent_ = true;
};

/// One Storage buffer per entry of `sizes` (bytes; at least 16 each, so that an empty
/// array still has a buffer to bind). A size over the device's storage-buffer range is an
/// Unsupported error: "<what> needs a storage buffer of N bytes (binding b); <device>
/// allows M".
[[nodiscard]] KODAWARI_INTERNAL Result<std::vector<Buffer>> create_storage_buffers(const Device& device,
                                                                                   std::span<const std::uint64_t> sizes,
                                                                                   const std::string& what);

}  // namespace kodawari::compute

namespace kodawari::gpu {
/// A range of a Vulkan buffer bound to a descriptor (the renderer's graphics sets).
struct BufferRange {
    vk::Buffer buffer;
    vk::DeviceSize offset = 0;
    vk::DeviceSize size = VK_WHOLE_SIZE;
};
}  // namespace kodawari::gpu
