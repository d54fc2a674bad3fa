#pragma once
// Recording, submitting and waiting as separate calls (in the style of Jolt's
// ComputeQueue: Execute, then Wait), so that a caller can record several domains' work
// into one submission, submit it, do host work, and wait only when it needs the results:
//
//     compute::Queue queue(device);
//     auto rec = queue.begin();                 // Result<Recording>
//     kernel.dispatch(rec.value(), push, groups);
//     compute::barrier(rec.value(), compute::Stage::Compute, compute::Stage::Host);
//     auto sub = queue.submit(std::move(rec).value());  // Result<Submission>
//     KW_TRY(sub.value().wait());

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "compute/buffer.hpp"
#include "core/internal_api.hpp"

namespace kodawari::compute {

/// Pipeline stages whose memory accesses a barrier orders (a bit set).
enum class Stage : std::uint32_t {
    Compute = 1,   ///< kernels (shader reads and writes)
    Transfer = 2,  ///< buffer copies
    Host = 4,      ///< the host's reads and writes of mapped memory
    Vertex = 8,    ///< vertex shaders of the renderer (reads)
    /// An application's draws reading the module's buffers: vertex input, vertex and
    /// fragment shaders (reads; only on a queue family that draws).
    Draw = 16,
};
[[nodiscard]] constexpr Stage operator|(Stage a, Stage b) {
    return static_cast<Stage>(static_cast<std::uint32_t>(a) | static_cast<std::uint32_t>(b));
}
[[nodiscard]] constexpr bool has(Stage set, Stage bit) { return (static_cast<std::uint32_t>(set) & static_cast<std::uint32_t>(bit)) != 0; }

/// Which of the two submission timestamps (Device::timestamp_ms is the time between them).
enum class Timestamp { Begin, End };

class Queue;
class StagingRing;

/// Commands being recorded: move-only; owns its command buffer until submitted (then the
/// Submission owns it) or destroyed unsubmitted (given back, nothing runs).
class KODAWARI_INTERNAL Recording {
public:
    Recording(Recording&& other) noexcept;
    Recording& operator=(Recording&& other) noexcept;
    Recording(const Recording&) = delete;
    Recording& operator=(const Recording&) = delete;
    ~Recording();

    /// Records into a command buffer the application owns, began and will submit (issue 11):
    /// nothing is submitted, waited for or freed here. Uploads go through `staging`'s
    /// current slot (never straight into mapped buffers, which frames still in flight may
    /// read; null: the recording uploads nothing); keep() is not available, there being
    /// no submission to tie a buffer to.
    [[nodiscard]] static Recording borrow(Device& device, VkCommandBuffer cmd, StagingRing* staging);

    [[nodiscard]] Device& device() const { return *device_; }
    /// Writes a submission timestamp (where the device has them; not in a borrowed
    /// command buffer, whose queries are the application's).
    void timestamp(Timestamp which);
    /// Keeps `buffer` (a staging buffer a recorded copy reads or writes) alive until the
    /// submission completes.
    void keep(Buffer buffer);
    /// The command buffer is the application's (borrow()).
    [[nodiscard]] bool borrowed() const { return borrowed_; }
    /// The ring a borrowed recording's uploads go through.
    [[nodiscard]] StagingRing* staging() const { return staging_; }
    /// The Vulkan command buffer (the implementation's; for the renderer's graphics commands).
    [[nodiscard]] const vk::raii::CommandBuffer& vulkan() const { return slot_.cmd; }

private:
    friend class Queue;
    friend class Submission;
    Recording(Device& device, gpu::CommandSlot slot) : device_(&device), slot_(std::move(slot)) {}
    void release();

    Device* device_;
    gpu::CommandSlot slot_;
    std::vector<Buffer> kept_;
    StagingRing* staging_ = nullptr;
    bool borrowed_ = false;
};

/// Host-visible upload buffers, one slot per frame in flight (Device::frames_in_flight):
/// the frame being recorded writes its input into its slot while the GPU may still read
/// the slots of the frames before it. The application's contract (docs/embedding.md):
/// when it records frame k, frame k - frames_in_flight has completed.
class StagingRing {
public:
    /// `bytes_per_frame`: the most one frame uploads (each upload rounded up to 16 bytes).
    [[nodiscard]] static Result<StagingRing> create(const Device& device, std::uint64_t bytes_per_frame, std::uint32_t frames);

    /// Moves to the next frame's slot (the oldest) and empties it.
    void next_frame();
    /// Copies `bytes` into the current slot: the buffer and offset a copy reads them from;
    /// an error when the slot is full (the frame uploads more than create() was told).
    [[nodiscard]] Result<std::pair<const Buffer*, std::uint64_t>> write(std::span<const std::byte> bytes);
    [[nodiscard]] std::uint64_t bytes_per_frame() const { return bytes_per_frame_; }

private:
    StagingRing() = default;
    std::vector<Buffer> slots_;
    std::uint64_t bytes_per_frame_ = 0;
    std::uint64_t used_ = 0;
    std::uint32_t current_ = 0;
};

/// Work submitted to the queue. wait() blocks until it completed; destroying an unwaited
/// Submission waits too, so that nothing it uses is freed while the device runs it.
class KODAWARI_INTERNAL Submission {
public:
    Submission(Submission&& other) noexcept;
    Submission& operator=(Submission&& other) noexcept;
    Submission(const Submission&) = delete;
    Submission& operator=(const Submission&) = delete;
    ~Submission();

    /// Waits (at most 600 s: a hung device must not hang the program). `gpu_ms` receives
    /// the time between the recording's timestamps, -1 without them. Once done, later
    /// calls return at once.
    [[nodiscard]] Result<void> wait(double* gpu_ms = nullptr);
    [[nodiscard]] bool pending() const { return device_ != nullptr; }

private:
    friend class Queue;
class StagingRing;
    explicit Submission(Recording recording);

    Device* device_ = nullptr;  // null once waited (or moved from)
    gpu::CommandSlot slot_;
    std::vector<Buffer> kept_;
};

/// The device's one queue.
class KODAWARI_INTERNAL Queue {
public:
    explicit Queue(Device& device) : device_(&device) {}

    /// A new recording (its timestamps reset).
    [[nodiscard]] Result<Recording> begin() const;
    /// Ends and submits `recording`; returns at once.
    [[nodiscard]] Result<Submission> submit(Recording recording) const;

private:
    Device* device_;
};

/// Orders the memory accesses of `before` (writes, and reads that later writes must not
/// overtake) before those of `after`, making the writes visible to them.
KODAWARI_INTERNAL void barrier(Recording& recording, Stage before, Stage after);

/// Records a copy of `bytes` bytes from `source` at `source_offset` to `target` at
/// `target_offset` (order it with barrier()).
KODAWARI_INTERNAL void copy(Recording& recording, const Buffer& source, std::uint64_t source_offset, const Buffer& target,
                            std::uint64_t target_offset, std::uint64_t bytes);

/// Writes `bytes` into a Storage buffer within `recording`: by memcpy now when the buffer
/// is mapped (so not while earlier, unfinished work reads it), else by a copy from a
/// staging buffer the recording keeps, ordered after earlier kernels and before later ones.
[[nodiscard]] KODAWARI_INTERNAL Result<void> upload(Recording& recording, const Buffer& buffer,
                                                    std::span<const std::byte> bytes);
/// upload() in a submission of its own, waited for (nothing to do when mapped).
[[nodiscard]] KODAWARI_INTERNAL Result<void> upload(Device& device, const Buffer& buffer, std::span<const std::byte> bytes);
/// Reads the first bytes.size() bytes of a Storage buffer that kernels wrote in earlier,
/// completed submissions: by memcpy when mapped, else through a readback buffer.
[[nodiscard]] KODAWARI_INTERNAL Result<void> download(Device& device, const Buffer& buffer, std::span<std::byte> bytes);

}  // namespace kodawari::compute
