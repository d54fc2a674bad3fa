#pragma once
/// @file
/// The narrow interface every bird backend implements (cpu-reference, cpu, vulkan).
/// The same tests run against each.

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "kodawari/core/api.hpp"
#include "kodawari/birds/world.hpp"
#include "kodawari/backends/device_data.hpp"
#include "kodawari/core/result.hpp"

namespace kodawari {

namespace compute {
class Device;
}

/// The bird backends' device buffers (DeviceData::buffer()).
namespace bird_buffers {
/// BirdPoseGpu per bird (<kodawari/shared/birds.h>): the last simulated frame's poses, one
/// slot of the backend's ring of frames.
inline constexpr std::string_view poses = "birds.poses";
}  // namespace bird_buffers

/// Which implementation runs the simulation.
enum class BackendKind { CpuReference, Cpu, Vulkan };

/// "cpu-reference", "cpu", "vulkan".
[[nodiscard]] KODAWARI_API std::string_view backend_name(BackendKind kind);

/// How the vulkan rod backend maps chains onto invocations (BackendOptions::rod_kernel).
enum class RodKernel {
    /// An invocation per chain, the template's constants in its registers
    /// (shaders/rods_step.comp): the default, and the fastest on lavapipe.
    PerChain,
    /// The same, with the template's constants once per workgroup in shared memory, read
    /// at each use (rods_step.comp built as rods_step_shared), to free registers on a GPU.
    /// Worlds of at most 32 templates (one dispatch each); load() refuses others.
    PerChainSharedConstants,
    /// A group of invocations per chain and one per joint (shaders/rods_lanes.comp): a
    /// lane's registers are one joint's and the state's loads consecutive across a
    /// subgroup, at the cost of barriers where the solver is sequential along the chain.
    /// Worlds of at most 32 templates without levels of detail, keyed examples, center
    /// frames or angle limits; load() refuses others (Unsupported, naming the option and
    /// what the world has).
    PerJoint,
};

/// Options for creating backends.
struct BackendOptions {
    std::string device;        ///< Vulkan device name substring or index ("" = best)
    bool validation = false;   ///< Khronos validation + synchronization validation
    /// Staging copies even where the device shares the host's memory (the discrete-GPU
    /// path; for tests on an integrated or CPU device).
    bool force_staging = false;
    unsigned threads = 0;      ///< cpu backend threads (0 = hardware concurrency)
    /// Invocations per workgroup of the vulkan backends' per-instance kernels (chains,
    /// birds, poses, flocking): 0 = their default (64); else a power of two from 32 to
    /// 1024 that the device allows. A variant to time on a GPU (`bench --workgroup-sizes`);
    /// the results are the same bits at every size. Others: InvalidInput naming it.
    unsigned workgroup_size = 0;
    /// The vulkan bird backend writes each frame's poses as six arrays of vec4, one per
    /// BirdPoseGpu field, instead of a record per bird: the same bytes, laid out so that a
    /// GPU's subgroup stores one field as one run. A variant to time on a GPU (`bench
    /// birds --pose-layouts records,fields`); nothing reads such poses, so simulate() with
    /// poses or diagnostics, recording and drawing are Unsupported with it. Ignored by the
    /// other backends.
    bool bird_pose_fields = false;
    /// The kernel the vulkan rod backend steps chains with (RodKernel): variants to time on
    /// a GPU (`bench chains --rod-kernels per-chain,shared-constants,per-joint`). The same
    /// solver in each, to rounding. Ignored by the other backends.
    RodKernel rod_kernel = RodKernel::PerChain;
    /// The Vulkan device a vulkan backend opens captures every kernel's statistics, where
    /// the driver offers VK_KHR_pipeline_executable_properties (registers, spills, shared
    /// memory: compute::Device::kernel_statistics()); `bench --kernel-statistics` prints
    /// them. Ignored with `context` (a device already open) and by the other backends.
    bool kernel_statistics = false;
    /// The cpu backend's SIMD instruction set: "" = the widest this machine runs, or one
    /// of available_simd_isas() ("avx512", "avx2", "sse4", "scalar"; kodawari/backends/simd.hpp).
    /// A name it cannot use makes make_cpu_*_backend() fail with InvalidInput.
    std::string isa;
    /// A Vulkan device to run on instead of opening one: a renderer's
    /// (render::Renderer::device_context()), so that the renderer draws straight from the
    /// backends' buffers on the same device. `device` and `validation` are then the
    /// context's. Null: each vulkan backend opens its own.
    std::shared_ptr<compute::Device> context{};
};

/// Where simulated frames go. Empty spans: the backend still does all the work but
/// keeps results on its side (benchmarks).
struct FrameOutput {
    std::span<gpu::BirdPose> poses;  ///< frames x birds, frame-major
    std::span<gpu::BirdDiag> diag;   ///< frames x birds, or empty
};

/// Simulates a BirdWorld frame after frame.
class KODAWARI_API BirdBackend {
public:
    virtual ~BirdBackend() = default;
    BirdBackend() = default;
    BirdBackend(const BirdBackend&) = delete;
    BirdBackend& operator=(const BirdBackend&) = delete;

    /// The backend's name ("vulkan").
    [[nodiscard]] virtual std::string_view name() const = 0;
    /// What it runs on ("llvmpipe (LLVM 15.0.6, 256 bits)", "2 threads").
    [[nodiscard]] virtual std::string device() const = 0;

    /// Takes the world (uploads it) and rewinds to frame 0.
    [[nodiscard]] virtual Result<void> load(const birds::BirdWorld& world) = 0;

    /// Simulates the next `frames` frames. `out.poses` must hold frames x birds entries
    /// or be empty; likewise `out.diag`. A world with driven birds (BirdWorld::driven)
    /// needs drive() first.
    [[nodiscard]] virtual Result<void> simulate(std::uint32_t frames, FrameOutput out) = 0;

    /// The motion the world's driven birds fly in the next simulate(): frames x
    /// BirdWorld::driven entries, frame-major (a flocking domain's output). Read during
    /// simulate() only: it must stay valid until then.
    [[nodiscard]] virtual Result<void> drive(std::span<const gpu::BirdMotionGpu> motion) {
        motion_ = motion;
        return {};
    }

    /// GPU time of the last simulate() in milliseconds, when the device has timestamps.
    [[nodiscard]] virtual double last_gpu_ms() const { return -1.0; }

    /// Validation messages seen so far (Vulkan with validation on; 0 otherwise).
    [[nodiscard]] virtual std::uint32_t validation_messages() const { return 0; }

    /// The backend's data on its device (the vulkan backend; null otherwise): after
    /// simulate(), bird_buffers::poses holds the last simulated frame's poses, also
    /// when simulate() was given no output; render::Renderer draws the birds from them
    /// without reading them back.
    [[nodiscard]] virtual const DeviceData* device_data() const { return nullptr; }

protected:
    /// What the last drive() gave: frames x driven, or empty.
    std::span<const gpu::BirdMotionGpu> motion_;
    /// An error when the world has driven birds and drive() gave too little for `frames`.
    [[nodiscard]] Result<void> check_motion(const birds::BirdWorld& world, std::uint32_t frames) const;
};

/// The threads a cpu backend made with `options` runs on: BackendOptions::threads, or the
/// hardware concurrency for 0.
[[nodiscard]] unsigned cpu_backend_threads(const BackendOptions& options);

/// Creates a cpu-reference or cpu bird backend (kodawari::sim). BackendKind::Vulkan is an
/// InvalidInput error naming kodawari::vulkan, whose make_bird_backend() makes every kind
/// (kodawari/vulkan/backend_factory.hpp).
[[nodiscard]] KODAWARI_API Result<std::unique_ptr<BirdBackend>> make_cpu_bird_backend(BackendKind kind,
                                                                                      const BackendOptions& options);

}  // namespace kodawari
