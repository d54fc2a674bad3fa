#pragma once
// The Vulkan runtime: instance (validation on request), the chosen device and its
// compute (or graphics + compute) queue, one-shot submissions with optional timestamps. Every handle is owned
// by a move-only vk::raii object.

#include <atomic>
#include <functional>
#include <memory>
#include <string>

#include <vulkan/vulkan_raii.hpp>

#include "kodawari/gpu_info.hpp"
#include "kodawari/result.hpp"

namespace kodawari::gpu {

struct ContextOptions {
    std::string device;       ///< index or name substring; "" = best (or env KODAWARI_DEVICE)
    bool validation = false;  ///< also on when env KODAWARI_VALIDATION=1
    /// The queue must do graphics too (the renderer). Compute-only contexts prefer a
    /// compute-only family (async compute on GPUs), which cannot draw.
    bool graphics = false;
};

class VulkanContext {
public:
    /// Opens the loader, creates the instance and the device. Errors say what is missing.
    [[nodiscard]] static Result<std::unique_ptr<VulkanContext>> create(const ContextOptions& options);

    VulkanContext(const VulkanContext&) = delete;
    VulkanContext& operator=(const VulkanContext&) = delete;
    ~VulkanContext();

    [[nodiscard]] const vk::raii::Device& device() const { return device_; }
    [[nodiscard]] const vk::raii::PhysicalDevice& physical_device() const { return physical_; }
    [[nodiscard]] const GpuDeviceInfo& info() const { return info_; }
    /// Device-local memory is also host-visible and coherent and the device shares the
    /// host's memory (integrated, CPU): buffers are mapped, no staging copies.
    [[nodiscard]] bool unified_memory() const { return unified_; }
    [[nodiscard]] std::uint32_t validation_messages() const { return messages_->load(); }
    [[nodiscard]] bool validation_enabled() const { return validation_; }

    /// Records commands with `record`, submits them and waits. When the device has
    /// timestamps, `gpu_ms` receives the time between the two timestamps `record` may
    /// write with write_timestamp().
    [[nodiscard]] Result<void> submit(const std::function<void(const vk::raii::CommandBuffer&)>& record,
                                      double* gpu_ms = nullptr);

    /// Writes timestamp 0 (begin) or 1 (end) into the submission's query pool.
    void write_timestamp(const vk::raii::CommandBuffer& cmd, std::uint32_t which, vk::PipelineStageFlagBits stage) const;

    /// Index of a memory type with all `required` flags, preferring `preferred` too.
    [[nodiscard]] Result<std::uint32_t> memory_type(std::uint32_t type_bits, vk::MemoryPropertyFlags required,
                                                    vk::MemoryPropertyFlags preferred = {}) const;

private:
    VulkanContext() = default;

    std::unique_ptr<vk::raii::Context> context_;  // first: outlives every handle
    vk::raii::Instance instance_{nullptr};
    vk::raii::DebugUtilsMessengerEXT messenger_{nullptr};
    vk::raii::PhysicalDevice physical_{nullptr};
    vk::raii::Device device_{nullptr};
    vk::raii::Queue queue_{nullptr};
    vk::raii::CommandPool pool_{nullptr};
    vk::raii::CommandBuffer command_buffer_{nullptr};
    vk::raii::Fence fence_{nullptr};
    vk::raii::QueryPool timestamps_{nullptr};
    GpuDeviceInfo info_;
    vk::PhysicalDeviceMemoryProperties memory_{};
    float timestamp_period_ns_ = 0.0f;
    std::uint64_t timestamp_mask_ = 0;
    std::uint32_t queue_family_ = 0;
    bool unified_ = false;
    bool validation_ = false;
    // Heap-allocated so the callback's pointer stays valid when the context moves.
    std::unique_ptr<std::atomic<std::uint32_t>> messages_ = std::make_unique<std::atomic<std::uint32_t>>(0);
};

/// Turns an exception from vulkan.hpp into an Error.
[[nodiscard]] Error vulkan_error(const std::string& what, const std::exception& e);

}  // namespace kodawari::gpu
