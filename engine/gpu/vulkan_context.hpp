#pragma once
// The Vulkan runtime: instance (validation on request), the chosen device and its
// compute (or graphics + compute) queue, one-shot submissions with optional timestamps. Every handle is owned
// by a move-only vk::raii object.

#include <atomic>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

#include <vulkan/vulkan_raii.hpp>

#include "core/internal_api.hpp"
#include "kodawari/vulkan/compute.hpp"
#include "kodawari/vulkan/gpu_info.hpp"
#include "kodawari/core/result.hpp"

namespace kodawari::gpu {

struct ContextOptions {
    std::string device;       ///< index or name substring; "" = best
    bool validation = false;  ///< Khronos validation + synchronization validation
    /// Staging copies even where the device shares the host's memory (the discrete-GPU
    /// path, for tests on an integrated or CPU device).
    bool force_staging = false;
    /// The queue must do graphics too (the renderer). Compute-only contexts prefer a
    /// compute-only family (async compute on GPUs), which cannot draw.
    bool graphics = false;
    /// Extra instance extensions (a window system's surface extensions, e.g. what
    /// glfwGetRequiredInstanceExtensions lists).
    std::vector<std::string> instance_extensions{};
    /// When set, called once with the new instance to create the surface of a window
    /// (the engine knows no window system; the viewer passes glfwCreateWindowSurface).
    /// The context then owns the surface, picks a queue family that can present to it and
    /// enables VK_KHR_swapchain.
    std::function<Result<VkSurfaceKHR>(VkInstance)> create_surface{};
    /// Enables VK_KHR_pipeline_executable_properties where the device offers it, so that
    /// every kernel's statistics are captured (compute::Device::kernel_statistics).
    bool capture_statistics = false;
};

/// A device the application created (issue 11): Kodawari runs on it and never destroys
/// it (kodawari/vulkan/vulkan_embed.hpp's VulkanDeviceHandles is the public form).
struct AdoptOptions {
    VkInstance instance = VK_NULL_HANDLE;
    VkPhysicalDevice physical_device = VK_NULL_HANDLE;
    VkDevice device = VK_NULL_HANDLE;
    std::uint32_t queue_family = 0;
    std::uint32_t queue_index = 0;
    PFN_vkGetInstanceProcAddr get_instance_proc_addr = nullptr;
    const VkAllocationCallbacks* allocator = nullptr;
    std::uint32_t api_version = 0;
    std::uint32_t frames_in_flight = 2;
};

/// A command buffer and the fence of its submission: what a compute::Recording records
/// into and a compute::Submission waits on. Recycled by the context (acquire_slot,
/// release_slot) so that a frame allocates nothing.
struct CommandSlot {
    vk::raii::CommandBuffer cmd{nullptr};
    vk::raii::Fence fence{nullptr};
};

/// compute::Device's one implementation (kodawari/vulkan/compute.hpp).
class KODAWARI_INTERNAL VulkanContext final : public compute::Device {
public:
    /// Opens the loader, creates the instance and the device. Errors say what is missing.
    [[nodiscard]] static Result<std::unique_ptr<VulkanContext>> create(const ContextOptions& options);
    /// Runs on the application's instance and device: creates only its own objects on them
    /// (a command pool for load() and read(), buffers, pipelines) with the application's
    /// allocation callbacks, and destroys neither. Errors name what the device lacks.
    [[nodiscard]] static Result<std::unique_ptr<VulkanContext>> adopt(const AdoptOptions& options);

    VulkanContext(const VulkanContext&) = delete;
    VulkanContext& operator=(const VulkanContext&) = delete;
    ~VulkanContext() override;

    [[nodiscard]] const vk::raii::Device& device() const { return device_; }
    [[nodiscard]] const vk::raii::PhysicalDevice& physical_device() const { return physical_; }
    [[nodiscard]] const GpuDeviceInfo& info() const override { return info_; }
    /// Device-local memory is also host-visible and coherent and the device shares the
    /// host's memory (integrated, CPU): buffers are mapped, no staging copies.
    [[nodiscard]] bool unified_memory() const override { return unified_; }
    [[nodiscard]] std::uint32_t validation_messages() const override { return messages_->load(); }
    [[nodiscard]] bool validation_enabled() const { return validation_; }
    [[nodiscard]] const vk::raii::Instance& instance() const { return instance_; }
    /// The window surface (null without ContextOptions::create_surface).
    [[nodiscard]] const vk::raii::SurfaceKHR& surface() const { return surface_; }
    /// The one queue (graphics, compute and, with a surface, present).
    [[nodiscard]] const vk::raii::Queue& queue() const { return queue_; }
    [[nodiscard]] std::uint32_t queue_family() const { return queue_family_; }
    /// The queue family also draws: barriers may name the vertex and fragment stages.
    [[nodiscard]] bool graphics_queue() const override { return graphics_queue_; }
    /// The instance and device are the application's (adopt()).
    [[nodiscard]] bool adopted() const { return adopted_; }
    /// Frames the application may have in flight (adopt(); 1 for the engine's own devices,
    /// which wait for each submission): the depth of the per-frame input rings.
    [[nodiscard]] std::uint32_t frames_in_flight() const override { return frames_in_flight_; }
    /// The application's allocation callbacks for every object created on the device
    /// (null: the driver's).
    [[nodiscard]] const vk::AllocationCallbacks* allocator() const { return allocator_; }

    /// Records commands with `record`, submits them and waits (compute::Queue's begin,
    /// submit and wait in one call). When the device has timestamps, `gpu_ms` receives the
    /// time between the two timestamps `record` may write with write_timestamp().
    [[nodiscard]] Result<void> submit(const std::function<void(const vk::raii::CommandBuffer&)>& record,
                                      double* gpu_ms = nullptr);

    /// A free command buffer and fence (compute::Queue::begin), new when none is free.
    [[nodiscard]] Result<CommandSlot> acquire_slot();
    /// Gives a slot back once its submission completed (or it was never submitted).
    void release_slot(CommandSlot slot);
    /// The submission timestamps' pool (null without timestamps).
    [[nodiscard]] const vk::raii::QueryPool& timestamp_pool() const { return timestamps_; }
    /// Milliseconds between timestamps 0 and 1 of the last completed submission that
    /// wrote both; -1 when the device has no timestamps or they are not written.
    [[nodiscard]] double timestamp_ms() const;

    /// Writes timestamp 0 (begin) or 1 (end) into the submission's query pool.
    void write_timestamp(const vk::raii::CommandBuffer& cmd, std::uint32_t which, vk::PipelineStageFlagBits stage) const;

    /// Bytes of kernel output read back to the host so far (download(), the bird
    /// backend's pose read back): what the viewer keeps at 0 per frame by drawing from
    /// the buffers where they are.
    [[nodiscard]] std::uint64_t read_back_bytes() const override { return read_back_bytes_; }
    void count_read_back(std::uint64_t bytes) { read_back_bytes_ += bytes; }
    /// Bytes of read-back buffers (host memory the device copies into) created so far: how
    /// a test checks that work reading nothing back pins no host memory for it.
    [[nodiscard]] std::uint64_t readback_buffer_bytes() const { return readback_buffer_bytes_; }
    void count_readback_buffer(std::uint64_t bytes) const { readback_buffer_bytes_ += bytes; }
    /// Submissions to the queue so far: how a test checks that recording submits nothing.
    [[nodiscard]] std::uint64_t submissions() const override { return submissions_; }
    void count_submission() { ++submissions_; }
    /// Kernels are created with VK_PIPELINE_CREATE_CAPTURE_STATISTICS_BIT_KHR and report
    /// their statistics through add_statistics().
    [[nodiscard]] bool captures_statistics() const { return captures_statistics_; }
    void add_statistics(compute::KernelStatistics statistics) const;
    [[nodiscard]] Result<std::vector<compute::KernelStatistics>> kernel_statistics() const override;

    /// Index of a memory type with all `required` flags, preferring `preferred` too.
    [[nodiscard]] Result<std::uint32_t> memory_type(std::uint32_t type_bits, vk::MemoryPropertyFlags required,
                                                    vk::MemoryPropertyFlags preferred = {}) const;

private:
    VulkanContext() = default;
    // The queue, command pool, timestamps and memory facts, once device_ exists.
    void finish_setup(bool force_staging, std::uint32_t queue_index = 0);

    std::unique_ptr<vk::raii::Context> context_;  // first: outlives every handle
    vk::raii::Instance instance_{nullptr};
    vk::raii::DebugUtilsMessengerEXT messenger_{nullptr};
    vk::raii::SurfaceKHR surface_{nullptr};  // after the instance: destroyed before it
    vk::raii::PhysicalDevice physical_{nullptr};
    vk::raii::Device device_{nullptr};
    vk::raii::Queue queue_{nullptr};
    vk::raii::CommandPool pool_{nullptr};
    std::vector<CommandSlot> free_slots_;  // after the pool: freed before it
    vk::raii::QueryPool timestamps_{nullptr};
    GpuDeviceInfo info_;
    vk::PhysicalDeviceMemoryProperties memory_{};
    float timestamp_period_ns_ = 0.0f;
    std::uint64_t timestamp_mask_ = 0;
    std::uint32_t queue_family_ = 0;
    std::uint64_t read_back_bytes_ = 0;
    mutable std::uint64_t readback_buffer_bytes_ = 0;  // counted by compute::Buffer::create
    std::uint64_t submissions_ = 0;
    bool unified_ = false;
    bool validation_ = false;
    bool graphics_queue_ = false;
    bool adopted_ = false;
    bool captures_statistics_ = false;
    std::string statistics_note_ = "kernel statistics: not asked for (BackendOptions::kernel_statistics)";
    mutable std::mutex statistics_mutex_;  // kernels may be created on several threads
    mutable std::vector<compute::KernelStatistics> statistics_;
    std::uint32_t frames_in_flight_ = 1;
    const vk::AllocationCallbacks* allocator_ = nullptr;
    // Heap-allocated so the callback's pointer stays valid when the context moves.
    std::unique_ptr<std::atomic<std::uint32_t>> messages_ = std::make_unique<std::atomic<std::uint32_t>>(0);
};

/// Turns an exception from vulkan.hpp into an Error that keeps its VkResult
/// (Error::vk_result). Called by guard(), the one boundary where they are caught.
[[nodiscard]] KODAWARI_INTERNAL Error vulkan_error(const std::string& what, const std::exception& e);

/// The one place where exceptions from vulkan.hpp become Errors (compute::guard is this
/// function too): runs `body`, which returns a Result, and turns what it throws into an
/// Error of kind Vulkan that keeps the VkResult (Error::vk_result) and names `what` was
/// being done. Callers that treat a result as control flow (a swapchain out of date)
/// check Error::vk_result instead of catching, so no other catch of vulkan.hpp's
/// exceptions is needed.
template <typename F>
[[nodiscard]] auto guard(std::string_view what, F&& body) -> std::invoke_result_t<F&> {
    try {
        return body();
    } catch (const std::exception& e) {
        return vulkan_error(std::string(what), e);
    }
}

}  // namespace kodawari::gpu
