#pragma once
/// @file
/// The narrow interface every pose backend implements (cpu-reference, cpu, vulkan), the
/// same shape as the rod backends (rod_backend.hpp): a crowd of instances of one rigged
/// glTF character, each playing one of its animation clips at its own time offset, is
/// evaluated into world matrices of every node. The same tests run against each.

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include <glm/glm.hpp>

#include "kodawari/core/api.hpp"
#include "kodawari/backends/backend.hpp"
#include "kodawari/animation/character.hpp"
#include "kodawari/animation/pose_instance.hpp"
#include "kodawari/core/result.hpp"
#include "kodawari/rods/solver.hpp"

namespace kodawari {

/// The pose backends' device buffers (DeviceData::buffer()).
namespace pose_buffers {
/// PoseMatrixGpu (<kodawari/shared/poses.h>), instances x nodes, instance-major: the world
/// matrices of the last evaluate().
inline constexpr std::string_view world = "poses.world";
}  // namespace pose_buffers

/// Checks instances against a character: every clip is -1 or an animation of it, every
/// time offset and placement is finite. Errors name the instance ("instance 17: clip 3
/// does not exist; the character has 1 animation"). Every backend's load() runs it.
[[nodiscard]] KODAWARI_API Result<void> check_instances(const animation::Character& character,
                                                        std::span<const PoseInstance> instances);

/// Evaluates a crowd of instances of one character at scene times.
class KODAWARI_API PoseBackend {
public:
    virtual ~PoseBackend() = default;
    PoseBackend() = default;
    PoseBackend(const PoseBackend&) = delete;
    PoseBackend& operator=(const PoseBackend&) = delete;

    /// The backend's name ("vulkan").
    [[nodiscard]] virtual std::string_view name() const = 0;
    /// What it runs on ("llvmpipe (LLVM 15.0.6, 256 bits)", "2 threads").
    [[nodiscard]] virtual std::string device() const = 0;

    /// Uploads the character (nodes, rest TRS, clips) and the instances (check_instances()
    /// must accept them; no instances is fine). `character` must outlive the backend's use
    /// of it; `instances` is copied.
    [[nodiscard]] virtual Result<void> load(const animation::Character& character, std::span<const PoseInstance> instances) = 0;

    /// Evaluates every instance at scene time `time` (s, finite). load() first.
    [[nodiscard]] virtual Result<void> evaluate(float time) = 0;

    /// As evaluate(time), but an instance whose `may_keep` entry is nonzero may keep the
    /// matrices of its last evaluation instead (one entry per instance; the first
    /// evaluation after load() evaluates every one). An allowance, not a promise: the cpu
    /// backend skips its batches (16 instances of one clip) whose instances all may; the
    /// others evaluate every instance. For callers that read only the other instances'
    /// matrices this frame (CrowdAnimator's clip rate of posed characters).
    [[nodiscard]] virtual Result<void> evaluate_some(float time, std::span<const std::uint8_t> may_keep) {
        (void)may_keep;
        return evaluate(time);
    }

    /// World matrices after the last evaluate(): instances x nodes, instance-major, nodes
    /// indexed like Character::nodes, each placement_matrix(placement) * the node's glTF
    /// world matrix (scale included). evaluate() first.
    [[nodiscard]] virtual Result<void> read(std::vector<glm::mat4>& world) = 0;

    /// The world matrices of the last evaluate() as read() gives them, in place, where
    /// the backend keeps them in host memory (cpu-reference, cpu): valid until the next
    /// load() or evaluate(). Empty where they live on a device (read() copies them then).
    /// Saves a crowd's copy per frame (10 000 instances of 50 nodes: 32 MB).
    [[nodiscard]] virtual std::span<const glm::mat4> host_world() const { return {}; }

    /// GPU time of the last evaluate() in milliseconds, when the device has timestamps.
    [[nodiscard]] virtual double last_gpu_ms() const { return -1.0; }
    /// Validation messages seen so far (Vulkan with validation on; 0 otherwise).
    [[nodiscard]] virtual std::uint32_t validation_messages() const { return 0; }

    /// The backend's data on its device (the vulkan backend; null otherwise): after
    /// evaluate(), pose_buffers::world holds the world matrices, for kernels and
    /// shaders that use them there.
    [[nodiscard]] virtual const DeviceData* device_data() const { return nullptr; }
};

/// Creates a cpu-reference or cpu pose backend (kodawari::sim); BackendKind::Vulkan is an
/// error, as for make_cpu_bird_backend().
[[nodiscard]] KODAWARI_API Result<std::unique_ptr<PoseBackend>> make_cpu_pose_backend(BackendKind kind,
                                                                                      const BackendOptions& options);

}  // namespace kodawari
