#pragma once
/// @file
/// The narrow interface every rod backend implements (cpu-reference, cpu, vulkan), the
/// same shape as the bird backends (backend.hpp). The same tests run against each.

#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "kodawari/core/api.hpp"
#include "kodawari/backends/backend.hpp"
#include "kodawari/core/result.hpp"
#include "kodawari/rods/chain_snapshot.hpp"
#include "kodawari/rods/world.hpp"

namespace kodawari {

/// The rod backends' device buffers (DeviceData::buffer()); element structs in
/// <kodawari/shared/rods.h>. The state, then this frame's input (written by the backend's
/// step, or on the device by the crowd animator's kernels).
namespace rod_buffers {
inline constexpr std::string_view chain_states = "chains.states";  ///< RodChainStateGpu per chain (root.position)
inline constexpr std::string_view motion = "chains.motion";        ///< RodJointMotionGpu per joint (x, relative to the root)
inline constexpr std::string_view spin = "chains.spin";            ///< RodJointSpinGpu per joint (q, the particle's orientation)
inline constexpr std::string_view reference = "chains.reference";  ///< RodTransformGpu per character
inline constexpr std::string_view roots = "chains.roots";          ///< RodTransformGpu per chain
inline constexpr std::string_view colliders = "chains.colliders";  ///< RodColliderGpu per collider
inline constexpr std::string_view keys = "chains.keys";            ///< RodTransformGpu per key source (RodFrame::keys)
inline constexpr std::string_view centers = "chains.centers";      ///< RodTransformGpu per center frame (RodFrame::centers)
}  // namespace rod_buffers

/// Simulates a RodWorld frame after frame.
class KODAWARI_API RodBackend {
public:
    virtual ~RodBackend() = default;
    RodBackend() = default;
    RodBackend(const RodBackend&) = delete;
    RodBackend& operator=(const RodBackend&) = delete;

    [[nodiscard]] virtual std::string_view name() const = 0;
    [[nodiscard]] virtual std::string device() const = 0;

    /// Takes the world (uploads it) and puts every chain at rest on the rest shape that
    /// `initial` gives it (rods::initial_state). `world` must be finalized and outlive
    /// the backend's use of it.
    [[nodiscard]] virtual Result<void> load(const rods::RodWorld& world, const rods::RodFrame& initial) = 0;

    /// Advances every chain by one frame (SPEC A.4): `frame` holds the kinematic input
    /// at the end of the frame (check_frame() must accept it).
    [[nodiscard]] virtual Result<void> step(const rods::RodFrame& frame) = 0;

    /// The state after the last step (or load).
    [[nodiscard]] virtual Result<void> read(ChainSnapshot& out) = 0;

    /// Every chain's full solver state, for parity tests: the GPU's state can be
    /// advanced by the CPU reference and compared.
    [[nodiscard]] virtual Result<void> read_states(std::vector<rods::ChainState>& out) = 0;

    /// GPU time of the last step in milliseconds, when the device has timestamps.
    [[nodiscard]] virtual double last_gpu_ms() const { return -1.0; }
    /// Validation messages seen so far (Vulkan with validation on; 0 otherwise).
    [[nodiscard]] virtual std::uint32_t validation_messages() const { return 0; }

    /// The backend's data on its device (the vulkan backend; null otherwise): after
    /// load(), the rod_buffers (state and this frame's input);
    /// render::Renderer draws the chains from them without reading them back.
    [[nodiscard]] virtual const DeviceData* device_data() const { return nullptr; }
};

/// Creates a cpu-reference or cpu rod backend (kodawari::sim); BackendKind::Vulkan is an
/// error, as for make_cpu_bird_backend().
[[nodiscard]] KODAWARI_API Result<std::unique_ptr<RodBackend>> make_cpu_rod_backend(BackendKind kind,
                                                                                    const BackendOptions& options);

/// One chain's frame with the CPU reference (SPEC A.3, A.2, A.5, A.4, and
/// docs/keyed-examples.md): its keyed weights (advancing `keys`, which start as
/// rods::initial_key_state), its rest shape from `frame`, the chain carried by its center's
/// motion (rods::follow_center from ChainState::center, which it updates), its level of
/// detail, then rods::step (or rods::step_posed). What every backend computes; exposed for
/// tests and `kodawari validate`. Returns false where the chain kept its state this frame
/// (rods::chain_rests: a posed or hidden chain between its turns; its keys and center are
/// still measured and carried, its idle frames counted): `rest_out` is then untouched.
KODAWARI_API bool step_chain_reference(const rods::RodWorld& world, std::uint32_t chain, const rods::RodFrame& frame,
                                       rods::ChainState& state, rods::KeyState& keys,
                                       rods::RestShape* rest_out = nullptr);

}  // namespace kodawari
