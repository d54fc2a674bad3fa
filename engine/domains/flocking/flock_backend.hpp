#pragma once
// What runs the flocking step (flock_domain.cpp opens one per backend kind): the CPU's
// (flock_cpu.cpp: cpu-reference one thread, cpu every thread, the same bits) and the GPU's
// (flock_vulkan.cpp).

#include <cstdint>
#include <memory>
#include <span>
#include <string>

#include <kodawari/shared/flocking.h>

#include "domains/flocking/flock_world.hpp"
#include "kodawari/backend.hpp"
#include "kodawari/result.hpp"

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
    [[nodiscard]] virtual std::string device() const = 0;
    [[nodiscard]] virtual std::uint32_t validation_messages() const { return 0; }
};

/// cpu-reference (threads = 1) or cpu.
[[nodiscard]] std::unique_ptr<FlockBackend> make_cpu_flock_backend(unsigned threads);
/// The GPU's, on `options.context`.
[[nodiscard]] Result<std::unique_ptr<FlockBackend>> make_vulkan_flock_backend(const BackendOptions& options);

}  // namespace kodawari::flocking
