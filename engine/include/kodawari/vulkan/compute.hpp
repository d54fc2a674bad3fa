#pragma once
/// @file
/// The compute layer (namespace kodawari::compute): what a domain's device code is written
/// against, in the shape of Jolt's ComputeSystem and ComputeQueue. Devices, buffers,
/// kernels, recordings and submissions, with no Vulkan type: the one implementation is
/// Vulkan (engine/gpu/), and what an application hands over in Vulkan's terms (its device,
/// its command buffers) is wrapped in kodawari/vulkan/vulkan_embed.hpp.
///
///     compute::Queue queue(device);
///     auto rec = queue.begin();                          // Result<Recording>
///     kernel.dispatch(rec.value(), push, groups);
///     compute::barrier(rec.value(), compute::Stage::Compute, compute::Stage::Host);
///     auto sub = queue.submit(std::move(rec).value());   // Result<Submission>
///     KW_TRY(sub.value().wait());
///
/// Recording, submitting and waiting are separate calls, so that a caller can record
/// several domains' work into one submission and wait only when it needs the results. A
/// Recording can also wrap an application's command buffer (borrow_command_buffer() in
/// kodawari/vulkan/vulkan_embed.hpp): then nothing is submitted or waited for here.

#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "kodawari/core/api.hpp"
#include "kodawari/vulkan/gpu_info.hpp"
#include "kodawari/core/result.hpp"

namespace kodawari::compute {

/// One compiled kernel as the driver describes it (VK_KHR_pipeline_executable_properties):
/// what a GPU run reads to see what a kernel costs the hardware, e.g. NVIDIA's register
/// count, local (spill) memory and shared memory. Names and units are the driver's.
struct KernelStatistics {
    std::string kernel;                         ///< the shader ("rods_step")
    std::vector<std::uint32_t> specialization;  ///< its specialization constants, by id
    struct Value {
        std::string executable;  ///< the driver's name for the compiled stage
        std::string name;        ///< "Register Count"
        std::string value;       ///< as the driver gives it: an integer, a float or true/false
    };
    std::vector<Value> values;
    /// Why there are none where a statistic could not be read (the kernel still runs).
    std::string note;
};

/// A device with one queue, shared (std::shared_ptr) by the backends, the domains and a
/// renderer that run on it. Made by the engine (a Simulation, a backend, a renderer) or
/// adopted from an application (kodawari::adopt_vulkan_device); never made by a caller.
class KODAWARI_API Device {
public:
    virtual ~Device();
    Device(const Device&) = delete;
    Device& operator=(const Device&) = delete;

    /// What it is and the limits that matter to kernels (name, storage-buffer range...).
    [[nodiscard]] virtual const GpuDeviceInfo& info() const = 0;
    /// Validation messages so far (0 without validation).
    [[nodiscard]] virtual std::uint32_t validation_messages() const = 0;
    /// Frames an application records ahead of the GPU on it (1 on the engine's own
    /// devices, which wait for each submission): the depth a StagingRing needs.
    [[nodiscard]] virtual std::uint32_t frames_in_flight() const = 0;
    /// Device memory is mapped into the host (integrated GPUs, CPU devices): Storage
    /// buffers are mapped and uploads are plain copies.
    [[nodiscard]] virtual bool unified_memory() const = 0;
    /// Its queue also draws: barriers may name Stage::Draw.
    [[nodiscard]] virtual bool graphics_queue() const = 0;
    /// Submissions to its queue so far: how a test checks that recording submits nothing.
    [[nodiscard]] virtual std::uint64_t submissions() const = 0;
    /// Bytes of kernel output read back to the host so far (every download() and pose
    /// read back): how a caller checks that a pipeline keeps its data on the device.
    [[nodiscard]] virtual std::uint64_t read_back_bytes() const = 0;
    /// The statistics of every kernel created on it so far, where it was opened to capture
    /// them (BackendOptions::kernel_statistics) and the driver offers them; otherwise
    /// Unsupported, saying which of the two is missing.
    [[nodiscard]] virtual Result<std::vector<KernelStatistics>> kernel_statistics() const;

protected:
    Device() = default;
};

/// What a buffer is for; decides its memory (see Buffer::create).
enum class Usage {
    Storage,   ///< read/written by kernels (storage or uniform); mapped when memory is unified
    Upload,    ///< host-visible source of copies
    Readback,  ///< host-visible (cached when possible) destination of copies
    Vertex,    ///< host-visible, coherent and mapped vertex (or index) buffer written by the CPU
};

/// A buffer and its memory, owned (move-only; freeing the memory unmaps it). Keep it no
/// longer than its Device.
class KODAWARI_API Buffer {
public:
    using Kind = Usage;  // the renderer's older name
    struct Native;       // the implementation's handles (engine/gpu/)

    /// `size` bytes of `usage`'s memory. Errors (kind Vulkan) name the size.
    [[nodiscard]] static Result<Buffer> create(const Device& device, std::uint64_t size, Usage usage);

    Buffer(Buffer&&) noexcept;
    Buffer& operator=(Buffer&&) noexcept;
    Buffer(const Buffer&) = delete;
    Buffer& operator=(const Buffer&) = delete;
    ~Buffer();

    [[nodiscard]] std::uint64_t size() const { return size_; }
    [[nodiscard]] Usage usage() const { return usage_; }
    /// Host address when the memory is mapped, else nullptr.
    [[nodiscard]] std::byte* mapped() const { return mapped_; }
    /// Makes device writes visible to the host (no-op on coherent memory).
    [[nodiscard]] Result<void> invalidate(const Device& device) const;
    /// The implementation's handles (engine-internal: engine/gpu/compute_vulkan.hpp).
    [[nodiscard]] const Native& native() const { return *native_; }

private:
    Buffer();
    std::unique_ptr<Native> native_;
    std::uint64_t size_ = 0;
    std::byte* mapped_ = nullptr;
    Usage usage_ = Usage::Storage;
    bool coherent_ = true;
};

/// One Storage buffer per entry of `sizes` (bytes; at least 16 each, so that an empty
/// array still has a buffer to bind). A size over the device's storage-buffer range is an
/// Unsupported error: "<what> needs a storage buffer of N bytes (binding b); <device>
/// allows M".
[[nodiscard]] KODAWARI_API Result<std::vector<Buffer>> create_storage_buffers(const Device& device,
                                                                              std::span<const std::uint64_t> sizes,
                                                                              const std::string& what);

/// How a kernel reads a binding.
enum class Binding {
    Storage,  ///< std430 storage buffer, read and written
    Uniform,  ///< std140 uniform buffer, read by every invocation (lavapipe loads it once for all lanes)
};

/// The whole of a buffer, in BufferView::size.
inline constexpr std::uint64_t kWholeSize = ~std::uint64_t{0};

/// A range of a Buffer bound to a binding (the whole buffer by default).
struct BufferView {
    const Buffer* buffer = nullptr;
    std::uint64_t offset = 0;
    std::uint64_t size = kWholeSize;
};

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

/// Which of the two submission timestamps (the device's time between them is what
/// Submission::wait reports).
enum class Timestamp { Begin, End };

class Queue;
class Submission;
class StagingRing;

/// Commands being recorded: move-only; owns its command buffer until submitted (then the
/// Submission owns it) or destroyed unsubmitted (given back, nothing runs), unless it
/// borrows the application's (kodawari/vulkan/vulkan_embed.hpp, borrow_command_buffer()).
class KODAWARI_API Recording {
public:
    struct Native;  // the implementation's command buffer (engine/gpu/)

    Recording(Recording&& other) noexcept;
    Recording& operator=(Recording&& other) noexcept;
    Recording(const Recording&) = delete;
    Recording& operator=(const Recording&) = delete;
    ~Recording();

    [[nodiscard]] Device& device() const { return *device_; }
    /// Another recording into the same command buffer, borrowed (this one keeps it),
    /// whose uploads go through `staging` (null: it uploads nothing): how a domain that
    /// keeps its own ring of per-frame uploads records into a recording it was handed.
    /// Use it only while this recording lives and is not submitted.
    [[nodiscard]] Recording share(StagingRing* staging) const;
    /// Writes a submission timestamp (where the device has them; not in a borrowed
    /// command buffer, whose queries are the application's).
    void timestamp(Timestamp which);
    /// Keeps `buffer` (a staging buffer a recorded copy reads or writes) alive until the
    /// submission completes. Not in a borrowed recording, which has no submission.
    void keep(Buffer buffer);
    /// The command buffer is not its own (an application's, or share()'s).
    [[nodiscard]] bool borrowed() const { return borrowed_; }
    /// The ring a borrowed recording's uploads go through.
    [[nodiscard]] StagingRing* staging() const { return staging_; }
    /// The implementation's command buffer (engine-internal: engine/gpu/compute_vulkan.hpp).
    [[nodiscard]] const Native& native() const { return *native_; }

    /// Wraps a command buffer the caller owns, began and will submit (engine-internal; the
    /// application's way in is kodawari::borrow_command_buffer).
    [[nodiscard]] static Recording borrow(Device& device, std::unique_ptr<Native> native, StagingRing* staging);

private:
    friend class Queue;
    friend class Submission;
    Recording(Device& device, std::unique_ptr<Native> native);
    void release();

    Device* device_ = nullptr;
    std::unique_ptr<Native> native_;
    std::vector<Buffer> kept_;
    StagingRing* staging_ = nullptr;
    bool borrowed_ = false;
};

/// Host-visible upload buffers, one slot per frame in flight (Device::frames_in_flight):
/// the frame being recorded writes its input into its slot while the GPU may still read
/// the slots of the frames before it. The application's contract (docs/embedding.md):
/// when it records frame k, frame k - frames_in_flight has completed.
class KODAWARI_API StagingRing {
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
class KODAWARI_API Submission {
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
    explicit Submission(Recording recording);

    Device* device_ = nullptr;  // null once waited (or moved from)
    std::unique_ptr<Recording::Native> native_;
    std::vector<Buffer> kept_;
};

/// The device's one queue.
class KODAWARI_API Queue {
public:
    explicit Queue(Device& device) : device_(&device) {}

    /// A new recording (its timestamps reset).
    [[nodiscard]] Result<Recording> begin() const;
    /// Ends and submits `recording` (not a borrowed one); returns at once.
    [[nodiscard]] Result<Submission> submit(Recording recording) const;

private:
    Device* device_;
};

/// The workgroup size a per-instance kernel runs at on `device`: `requested` (a caller's
/// BackendOptions::workgroup_size, 0 = `preferred`) checked to be a power of two from 32
/// to 1024 within the device's maxComputeWorkGroupSize[0] and
/// maxComputeWorkGroupInvocations. The kernel takes it as a specialization constant
/// (`layout(local_size_x_id = ...)`), so one shader serves every size. InvalidInput
/// naming `what` (the option) otherwise.
[[nodiscard]] KODAWARI_API Result<std::uint32_t> workgroup_size(const Device& device, unsigned requested, std::uint32_t preferred,
                                                                 std::string_view what = "BackendOptions::workgroup_size");
/// A workgroup size every caller may ask for: a power of two from 32 to 1024 (whether a
/// device allows it is workgroup_size()'s question). One rule for the C++, C and command-line
/// checks.
[[nodiscard]] constexpr bool is_workgroup_size(std::uint64_t n) { return n >= 32 && n <= 1024 && (n & (n - 1)) == 0; }
/// Workgroups of `size` invocations that cover `count` instances.
[[nodiscard]] constexpr std::uint32_t groups_for(std::uint64_t count, std::uint32_t size) {
    return static_cast<std::uint32_t>((count + size - 1) / size);
}

/// A compute kernel: the pipeline of a SPIR-V shader with its binding layout, push
/// constants and specialization constants, and its one set of buffer bindings.
class KODAWARI_API Kernel {
public:
    struct Native;  // the implementation's pipeline and descriptor set (engine/gpu/)

    /// A kernel of the engine's own shaders/<shader> (its SPIR-V embedded in the library):
    /// buffers at bindings 0..n-1 of `bindings`' kinds, `push_bytes` of push constants,
    /// and 32-bit specialization constants with ids 0..m-1.
    [[nodiscard]] static Result<Kernel> create(const Device& device, std::string_view shader, std::span<const Binding> bindings,
                                               std::uint32_t push_bytes, std::span<const std::uint32_t> specialization = {});
    /// The same from SPIR-V the caller holds (a domain's own kernel, compiled outside
    /// the engine); `name` names it in errors. `spirv` is read during the call only.
    [[nodiscard]] static Result<Kernel> create(const Device& device, std::string_view name, std::span<const std::uint32_t> spirv,
                                               std::span<const Binding> bindings, std::uint32_t push_bytes,
                                               std::span<const std::uint32_t> specialization = {});

    Kernel(Kernel&&) noexcept;
    Kernel& operator=(Kernel&&) noexcept;
    Kernel(const Kernel&) = delete;
    Kernel& operator=(const Kernel&) = delete;
    ~Kernel();

    /// Points binding i at views[i] (as many views as bindings). Only while no pending
    /// submission uses the kernel.
    void bind(std::span<const BufferView> views) const;
    /// Points binding i at the whole of *buffers[i].
    void bind(std::span<const Buffer* const> buffers) const;

    /// Records: binds the kernel and its buffers, pushes constants, dispatches groups_x
    /// workgroups.
    void dispatch(Recording& recording, std::span<const std::byte> push, std::uint32_t groups_x) const;
    /// The implementation's objects (engine-internal: engine/gpu/compute_vulkan.hpp).
    [[nodiscard]] const Native& native() const { return *native_; }

private:
    Kernel();
    std::unique_ptr<Native> native_;
};

/// Orders the memory accesses of `before` (writes, and reads that later writes must not
/// overtake) before those of `after`, making the writes visible to them.
KODAWARI_API void barrier(Recording& recording, Stage before, Stage after);

/// Records a copy of `bytes` bytes from `source` at `source_offset` to `target` at
/// `target_offset` (order it with barrier()).
KODAWARI_API void copy(Recording& recording, const Buffer& source, std::uint64_t source_offset, const Buffer& target,
                       std::uint64_t target_offset, std::uint64_t bytes);

/// Writes `bytes` into a Storage buffer within `recording`: by memcpy now when the buffer
/// is mapped (so not while earlier, unfinished work reads it), else by a copy from a
/// staging buffer the recording keeps, ordered after earlier kernels and before later
/// ones; in a borrowed recording, always by a copy from its StagingRing.
[[nodiscard]] KODAWARI_API Result<void> upload(Recording& recording, const Buffer& buffer, std::span<const std::byte> bytes);
/// upload() in a submission of its own, waited for (nothing to do when mapped).
[[nodiscard]] KODAWARI_API Result<void> upload(Device& device, const Buffer& buffer, std::span<const std::byte> bytes);
/// Reads the first bytes.size() bytes of a Storage buffer that kernels wrote in earlier,
/// completed submissions: by memcpy when mapped, else through a readback buffer.
[[nodiscard]] KODAWARI_API Result<void> download(Device& device, const Buffer& buffer, std::span<std::byte> bytes);

}  // namespace kodawari::compute
