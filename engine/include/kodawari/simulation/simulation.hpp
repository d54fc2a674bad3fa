#pragma once
/// @file
/// The engine's one entry point for simulating a scene (issue 19), what `kodawari run`,
/// `render`, `view` and `bench` and embedding applications use, as Box2D's `b2World_Step`
/// or Jolt's `PhysicsSystem::Update` are: it owns the domains of a scene (kodawari/simulation/domain.hpp:
/// the flocks' birds, the characters' chains, an application's own) on backends of one
/// kind on one device, and steps them frame after frame in their dependency order, so
/// that no caller has to know it. It names no domain: what is particular to one
/// (kodawari/domains/birds.hpp, chains.hpp) is reached through that domain's header.
///
/// A Simulation is made from a scene file, a parsed Scene or a scene built in code; its
/// outputs are read back through its domains or, for drawing, left where they were
/// computed (draw_on()).

#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "kodawari/core/api.hpp"
#include "kodawari/backends/backend.hpp"
#include "kodawari/simulation/domain.hpp"
#include "kodawari/core/result.hpp"
#include "kodawari/scene/scene.hpp"

namespace kodawari {

namespace render {
class Renderer;
}
namespace compute {
class Recording;
}

/// One of `count` parts of a scene's instances, for baking a scene over several processes
/// or machines (issue 15; kodawari/simulation/shards.hpp). Shard `index` holds instances
/// [index * n / count, (index + 1) * n / count) of each domain's n (the scene's birds, its
/// character instances): contiguous ranges, in the scene's order, that cover it once. The scene is built whole (every random draw made) before it is cut, so an
/// instance's frames do not depend on `count`.
struct Shard {
    std::uint32_t index = 0;
    std::uint32_t count = 1;  ///< 1: the whole scene
};

/// The range shard `shard` holds of `n` instances (asserts index < count).
[[nodiscard]] KODAWARI_API InstanceRange shard_range(std::uint32_t n, Shard shard);

/// One domain's part of a shard: instances `range` of the scene's `scene_count`.
struct ShardPart {
    std::string instances;  ///< what they are called (Domain::instance_noun(): "birds")
    InstanceRange range;
    std::uint32_t scene_count = 0;
};

/// Which of a scene's instances a Simulation runs: per domain, in the Simulation's
/// domain order.
struct ShardInfo {
    Shard shard;
    std::vector<ShardPart> parts;
    /// The part of the instances called `instances` (an empty one when none are).
    [[nodiscard]] KODAWARI_API ShardPart part(std::string_view instances) const;
};

/// The most frames a Simulation runs (SimulationOptions::frames; `kodawari run --frames`):
/// 46 hours at 60 frames a second.
inline constexpr std::uint32_t kMaxSimulationFrames = 10'000'000;

/// How a Simulation runs.
struct SimulationOptions {
    /// The backends' kind; none: "auto", vulkan when a GPU opens and can hold the scene
    /// (its buffers within the device's limits), else cpu (Simulation::fallback_reason()
    /// then says why): also when the device is a CPU (lavapipe; auto_passes_over()), where
    /// the cpu backend is several times faster, unless BackendOptions::device names it.
    /// A device asked for that matches none is an error, never a fallback.
    std::optional<BackendKind> backend{};
    /// Device, validation, cpu threads, and a device to run on (a renderer's); without
    /// one, the vulkan backends share one device the Simulation opens.
    BackendOptions options{};
    /// Simulate this many frames instead of the scene's, in [1, kMaxSimulationFrames].
    std::optional<std::uint32_t> frames{};
    /// With the vulkan backends: a domain's inputs that another domain makes on the same
    /// device are written there (the rigged characters' rod input from their poses;
    /// nothing read back per frame); false keeps them on the host (benchmarks compare the
    /// two). DomainSetup::device_inputs.
    bool device_inputs = true;
    /// Simulate this part of the scene's instances only (the default: all of them).
    Shard shard{};
};

/// A scene simulated frame after frame on backends of one kind.
class KODAWARI_API Simulation {
public:
    /// Loads the scene file at `path` (SCENE.json) and opens its domains' backends.
    [[nodiscard]] static Result<std::unique_ptr<Simulation>> open(const std::string& path, const SimulationOptions& options);
    /// Opens the backends for a scene parsed (parse_scene) or built in code: the scene's
    /// domains (build_scene_domains()) and then `domains`, an application's own, stepped
    /// after the scene's unless their inputs say otherwise. Bad definitions (two domains,
    /// channels or buffers of one name, an input nothing produces, a cycle) are InvalidInput errors
    /// naming the domain (order_domains()).
    [[nodiscard]] static Result<std::unique_ptr<Simulation>> create(Scene scene, const SimulationOptions& options,
                                                                    std::vector<std::unique_ptr<Domain>> domains = {});

    ~Simulation();
    Simulation(const Simulation&) = delete;
    Simulation& operator=(const Simulation&) = delete;

    [[nodiscard]] const Scene& scene() const;
    /// The domains, in the order they step.
    [[nodiscard]] std::span<Domain* const> domains() const;
    /// The domain named `name`; null when there is none.
    [[nodiscard]] Domain* domain(std::string_view name) const;
    /// Every domain's channels (Domain::channels()) as opened, in step order.
    [[nodiscard]] std::span<const ChannelInfo> channels() const;
    /// The part of the scene this simulation runs (SimulationOptions::shard).
    [[nodiscard]] const ShardInfo& shard() const;
    /// The kind every backend is of ("auto" resolved).
    [[nodiscard]] BackendKind backend() const;
    /// Whether record() can run: the vulkan backends on the application's device
    /// (SimulationOptions::options.context given).
    [[nodiscard]] bool can_record() const;
    /// Why "auto" runs on the CPU ("" when it did not fall back).
    [[nodiscard]] const std::string& fallback_reason() const;
    /// What the backends run on ("llvmpipe (LLVM 15.0.6, 256 bits)", "2 threads").
    [[nodiscard]] std::string device() const;
    /// Frames of the simulation: SimulationOptions::frames, else the scene's.
    [[nodiscard]] std::uint32_t frame_count() const;
    /// The frame simulated last; none before the first step().
    [[nodiscard]] std::optional<std::uint32_t> frame() const;

    /// Simulates the next `frames` frames (the first step() simulates frame 0); at most
    /// frame_count() in all. `out` names domains' channels to fill with every frame
    /// simulated (ChannelOutput; a name no domain has is an error).
    [[nodiscard]] Result<void> step(std::uint32_t frames = 1, std::span<const ChannelOutput> out = {});
    /// The next frame of every domain recorded into `recording` (kodawari/vulkan/compute.hpp), on
    /// the device the Simulation runs on: the vulkan backends, SimulationOptions::
    /// options.context an adopted device, and `recording` the application's command
    /// buffer (borrow_command_buffer(), kodawari/vulkan/vulkan_embed.hpp), each domain's work
    /// between barriers against the application's (docs/embedding.md). Nothing is
    /// submitted or waited for but what the domains say (Domain::record()); the frame's
    /// state is in the domains' buffers once the application's submission completed, and
    /// the application keeps at most VulkanDeviceHandles::frames_in_flight frames recorded
    /// ahead of the GPU. Errors: not the vulkan backends, a recording on another device,
    /// past the last frame (InvalidInput), a domain that cannot record (Unsupported,
    /// naming it).
    [[nodiscard]] Result<void> record(compute::Recording& recording);
    /// record() into `cmd`, a command buffer of the application's in the recording state
    /// (borrow_command_buffer() on the Simulation's device, then record()). A null `cmd`
    /// is InvalidInput.
    [[nodiscard]] Result<void> record(VkCommandBuffer cmd);
    /// Where a domain's named device buffer is now (Domain::buffers(); the scene's:
    /// bird_buffers::poses, rod_buffers::chain_states, motion and spin), to bind in the
    /// application's shaders after step() or record(). The range can move with the frames
    /// (the birds' pose ring): ask again after each. Errors (InvalidInput): a name no
    /// domain has (the message lists those it has), or the buffer not on a device (the
    /// cpu backends, or before the first frame).
    [[nodiscard]] Result<VulkanBufferRange> buffer(std::string_view name) const;
    /// Simulates up to frame `target` (clamped to the last): forwards from the current
    /// frame, or again from frame 0 when going back. Nothing when it is the current one.
    [[nodiscard]] Result<void> seek(std::uint32_t target);

    /// How the state reaches a renderer (kodawari::DrawSource).
    using DrawSource = kodawari::DrawSource;
    /// Hands the renderer what it draws of this simulation from now on (each domain's
    /// part); the renderer must outlive that use or be given another simulation.
    [[nodiscard]] Result<void> show_on(render::Renderer& renderer);
    /// This frame's state of every domain to the renderer given to show_on().
    [[nodiscard]] Result<void> draw_on(render::Renderer& renderer, DrawSource source = DrawSource::Device);

    /// Validation messages of every backend (one device shared: its count).
    [[nodiscard]] std::uint32_t validation_messages() const;

private:
    struct Impl;
    explicit Simulation(std::unique_ptr<Impl> impl);
    std::unique_ptr<Impl> impl_;
};

/// "auto" and the backends' names: "cpu-reference", "cpu", "vulkan"; none for auto.
[[nodiscard]] KODAWARI_API Result<std::optional<BackendKind>> parse_backend_choice(std::string_view name);

}  // namespace kodawari
