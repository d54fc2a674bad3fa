#pragma once
// What runs the flocking step (flock_domain.cpp opens one per backend kind): the CPU's
// (flock_cpu.cpp: cpu-reference one thread, cpu every thread, the same bits) and the GPU's
// (flock_vulkan.cpp).

#include <cstdint>
#include <memory>
#include <span>
#include <string>

#include <vulkan/vulkan_core.h>

#include <kodawari/shared/flocking.h>

#include "domains/flocking/flock_world.hpp"
#include "kodawari/backends/backend.hpp"
#include "kodawari/backends/device_data.hpp"
#include "kodawari/simulation/domain.hpp"
#include "kodawari/domains/flocking.hpp"
#include "kodawari/core/result.hpp"

namespace kodawari::compute {
class Buffer;
}

namespace kodawari::flocking {

class FlockBackend {
public:
    virtual ~FlockBackend() = default;
    /// Takes `world` (it must outlive the backend's use of it) and sets frame 0's state.
    [[nodiscard]] virtual Result<void> load(const FlockWorld& world) = 0;
    /// Advances `frames` frames from the current state, frame k with flocks[k x flocks]
    /// and agents[k x agents] (FlockWorld::frame_inputs(), then the application's:
    /// agents.size() / frames a frame), writing each frame's motion to out[k x birds].
    [[nodiscard]] virtual Result<void> advance(std::uint32_t frames, std::span<const gpu::FlockParamsGpu> flocks,
                                               std::span<const gpu::FlockAgentGpu> agents, std::span<gpu::BirdMotionGpu> out) = 0;
    /// One frame recorded into `cmd`, an application's command buffer on the backend's
    /// device (Simulation::record): `first` (frame 0) puts the world's first motion in
    /// motion_buffer() (a submission of its own, waited for), any other frame records its
    /// substeps with `flocks` and `agents` (one frame's) copied in through a ring of
    /// Device::frames_in_flight() staging slots, between the embedding barriers. The
    /// frame's motion is then in motion_buffer() (BirdMotionGpu per bird) once the
    /// application's submission completed; nothing is read back. Unsupported on the CPU.
    /// `device_agents` more agents follow `agents` (the range device_agents()), written by
    /// the application before this recording (set_flock_device_agents): not copied in.
    [[nodiscard]] virtual Result<void> record(compute::Recording& recording, bool first, std::span<const gpu::FlockParamsGpu> flocks,
                                              std::span<const gpu::FlockAgentGpu> agents, std::uint32_t device_agents) {
        (void)recording, (void)first, (void)flocks, (void)agents, (void)device_agents;
        return make_error(Error::Kind::Unsupported, "the flocking step records into a command buffer on the vulkan backend only");
    }
    /// Where record() leaves the frame's motion; null on the CPU.
    [[nodiscard]] virtual const compute::Buffer* motion_buffer() const { return nullptr; }
    /// Where record() reads the application's agents written on the device
    /// (FlockAgentGpu each, kMaxFlockAgents after the scene's); no buffer on the CPU.
    [[nodiscard]] virtual DeviceSpan device_agents() const { return {}; }
    [[nodiscard]] virtual std::string device() const = 0;
    /// Its time since load() (kodawari/domains/flocking.hpp); zeros where not measured.
    [[nodiscard]] virtual FlockingTiming timing() const { return {}; }
    /// profile_flocking() (kodawari/domains/flocking.hpp) with one frame's inputs.
    [[nodiscard]] virtual Result<FlockingTiming> profile(std::uint32_t frames, std::span<const gpu::FlockParamsGpu> flocks,
                                                         std::span<const gpu::FlockAgentGpu> agents) {
        (void)frames, (void)flocks, (void)agents;
        return make_error(Error::Kind::Unsupported, "profile_flocking: the CPU backends time the flocking step's parts as they "
                                                    "run (flocking_timing)");
    }
    [[nodiscard]] virtual std::uint32_t validation_messages() const { return 0; }
};

/// Where the flocking domain `domain` leaves a recorded frame's motion (FlockBackend::
/// motion_buffer()); null for another domain or off the vulkan backend.
[[nodiscard]] const compute::Buffer* flocking_motion_buffer(const Domain& domain);

/// cpu-reference: flock_body.glsl bird after bird on one thread.
[[nodiscard]] std::unique_ptr<FlockBackend> make_reference_flock_backend();
/// cpu: the same rules over `options`' threads with the hand-tuned search of its
/// instruction set (options.isa; an unknown one is an error naming it).
[[nodiscard]] Result<std::unique_ptr<FlockBackend>> make_cpu_flock_backend(const BackendOptions& options);
/// The GPU's, on `options.context`.
[[nodiscard]] Result<std::unique_ptr<FlockBackend>> make_vulkan_flock_backend(const BackendOptions& options);

}  // namespace kodawari::flocking
