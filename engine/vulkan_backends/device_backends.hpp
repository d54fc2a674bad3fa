#pragma once
// The vulkan backends' engine-internal side, written against the compute layer: the
// device they run on, recording a step into a caller's recording (so that several
// domains' work goes into one submission), and kinematic input written on the device.

#include <cstdint>
#include <memory>

#include "kodawari/vulkan/compute.hpp"
#include "kodawari/backends/backend.hpp"
#include "kodawari/backends/pose_backend.hpp"
#include "kodawari/backends/rod_backend.hpp"
#include "kodawari/vulkan/vulkan_embed.hpp"

namespace kodawari {

/// The device a vulkan backend runs on: `options.context` when set (shared with a
/// renderer; never destroyed by the backend while others hold it), else a new compute
/// device for `options.device` and `options.validation`.
[[nodiscard]] Result<std::shared_ptr<compute::Device>> backend_context(const BackendOptions& options);

/// The vulkan backends, made by make_bird_backend() and the others (backend_factory.cpp).
[[nodiscard]] Result<std::unique_ptr<BirdBackend>> make_vulkan_bird_backend(const BackendOptions& options);
[[nodiscard]] Result<std::unique_ptr<RodBackend>> make_vulkan_rod_backend(const BackendOptions& options);
[[nodiscard]] Result<std::unique_ptr<PoseBackend>> make_vulkan_pose_backend(const BackendOptions& options);

/// Records kernels that write part of a step's kinematic input where the vulkan rod
/// backend keeps it: after the frame's input has been written, before the step's
/// dispatch, in the same recording. `rods` is the rod backend's device data.
class RodInputWriter {
public:
    virtual ~RodInputWriter() = default;
    virtual void record(compute::Recording& recording, const DeviceData& rods) const = 0;
};

/// Where `span` (a backend's buffer, non-null) is, as an application binds it: what
/// vulkan_buffer() and the domains' Domain::buffer() hand out.
[[nodiscard]] inline VulkanBufferRange vulkan_range(const DeviceSpan& span) {
    return vulkan_range(*span.buffer, span.items * span.per_item, span.element_bytes, VkDeviceSize{span.first} * span.element_bytes);
}

/// Who reads what the module writes, in an application's command buffer: its kernels,
/// copies and, on a queue family that draws, its draws (docs/embedding.md,
/// "Synchronization"). The barriers around an embedded step name these stages.
[[nodiscard]] inline compute::Stage embedding_consumers(const compute::Device& device) {
    using compute::Stage;
    return device.graphics_queue() ? Stage::Compute | Stage::Transfer | Stage::Draw : Stage::Compute | Stage::Transfer;
}

/// What the vulkan rod backend adds to RodBackend inside the engine.
class DeviceRodBackend {
public:
    virtual ~DeviceRodBackend() = default;
    /// Part of each step's kinematic input written on the device instead of taken from
    /// the frame (CrowdAnimator::write_inputs_on); null removes it. Shared ownership: the
    /// writer and what it reads stay alive while the backend may step.
    virtual void set_input_writer(std::shared_ptr<const RodInputWriter> writer) = 0;
    /// The loaded world (null before load()).
    [[nodiscard]] virtual const rods::RodWorld* world() const = 0;
    /// The device it runs on (kernels that feed it are created there).
    [[nodiscard]] virtual compute::Device& compute_device() const = 0;
    /// step() without submitting or waiting: records the frame's input writes and the
    /// step's dispatch into `recording` (a recording of this backend's device). Where the
    /// input buffers are mapped, the input is written now, so the recording must be
    /// submitted (and complete) before the next record_step or step. The state is the
    /// new frame's once the caller's submission completed.
    [[nodiscard]] virtual Result<void> record_step(compute::Recording& recording, const rods::RodFrame& frame) = 0;
    /// record_step into a borrowed recording, the application's command buffer
    /// (kodawari/vulkan/vulkan_embed.hpp): the input through a ring of
    /// Device::frames_in_flight() staging slots, the barriers of embedding_consumers()
    /// before and after. Checks everything before recording.
    [[nodiscard]] virtual Result<void> record_external(compute::Recording& recording, const rods::RodFrame& frame) = 0;
};

/// What the vulkan bird backend adds to BirdBackend inside the engine.
class DeviceBirdBackend {
public:
    virtual ~DeviceBirdBackend() = default;
    /// The device it runs on.
    [[nodiscard]] virtual compute::Device& compute_device() const = 0;
    /// simulate(frames, {}) without submitting or waiting: records the dispatch of the
    /// next `frames` frames into `recording` (a recording of this backend's device);
    /// bird_buffers::poses is the last of them once the caller's submission completed.
    [[nodiscard]] virtual Result<void> record_simulate(compute::Recording& recording, std::uint32_t frames) = 0;
    /// record_simulate into a borrowed recording (the application's command buffer), between the barriers of
    /// embedding_consumers(). Birds flown by another domain (BirdWorld::driven) take one
    /// frame's motion from `motion` (BirdMotionGpu per driven bird, from its start: the
    /// flocking domain's buffer, written earlier in the same command buffer), copied in
    /// on the device; `frames` is then 1. Without driven birds `motion` is unused.
    [[nodiscard]] virtual Result<void> record_external(compute::Recording& recording, std::uint32_t frames,
                                                        const compute::Buffer* motion) = 0;
    /// The poses' ring as the kernel writes it (records, or fields with
    /// BackendOptions::bird_pose_fields), after load(): what a test compares the layouts by.
    [[nodiscard]] virtual const compute::Buffer& pose_ring() const = 0;
};

/// What the vulkan pose backend adds to PoseBackend inside the engine.
class DevicePoseBackend {
public:
    virtual ~DevicePoseBackend() = default;
    /// The device it runs on.
    [[nodiscard]] virtual compute::Device& compute_device() const = 0;
    /// evaluate(time) recorded into a borrowed recording (the application's command
    /// buffer), between the barriers of embedding_consumers().
    [[nodiscard]] virtual Result<void> record_external(compute::Recording& recording, float time) = 0;
};

}  // namespace kodawari
