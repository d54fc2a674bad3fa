#pragma once
/// @file
/// The domain contract (issue 31): what one kind of simulated thing (a flock's birds,
/// characters' chains, an application's own particles) gives the Simulation facade, so
/// that the facade steps, shards, draws and reads back every domain the same way and
/// names none. As Jolt's hair is updated through a ComputeSystem it does not own, a domain
/// is handed the backend kind and device to run on and the frames to simulate; what it
/// simulates, and how, is its own.
///
/// A Simulation holds a list of domains: the scene's (build_scene_domains()) and any an
/// application adds (Simulation::create's `domains`). Each declares the named outputs it
/// produces and the inputs it reads; the Simulation steps producers before their readers
/// and refuses, when it is made, a definition it cannot order (check_domains()).

#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include <vulkan/vulkan_core.h>

#include "kodawari/core/api.hpp"
#include "kodawari/backends/backend.hpp"
#include "kodawari/vulkan/vulkan_embed.hpp"
#include "kodawari/core/result.hpp"

namespace kodawari {

namespace render {
class Renderer;
}
namespace compute {
class Recording;
}

class Simulation;
struct Scene;

/// Instances [begin, end) of a scene.
struct InstanceRange {
    std::uint32_t begin = 0;
    std::uint32_t end = 0;
    [[nodiscard]] std::uint32_t size() const { return end - begin; }
};

/// Per-frame data a domain hands out by name ("birds.poses"): `elements` of
/// `element_bytes` bytes each frame, for the instances it holds.
struct ChannelInfo {
    std::string name;
    std::uint32_t element_bytes = 0;
    std::uint64_t elements = 0;
    /// A diagnostic (what a trace records: rest shapes, view weights), not needed to write
    /// the domain's glTF; part files of a sharded bake do not keep them.
    bool diagnostic = false;
};

/// The most frames a bake hands over at once (kodawari/simulation/bake.hpp, bake_chunk_frames()).
inline constexpr std::uint32_t kMaxBakeFrames = 120;

/// Where step() writes a channel's frames: frames x elements x element_bytes bytes,
/// frame-major; a channel the domain does not have is an error naming it.
struct ChannelOutput {
    std::string_view name;
    std::span<std::byte> bytes;
};

/// What a domain runs on, given to Domain::open().
struct DomainSetup {
    BackendKind kind = BackendKind::Cpu;
    /// With BackendKind::Vulkan, `options.context` is the device every domain shares.
    BackendOptions options{};
    /// Inputs that another domain produces on the same device are written there by the
    /// reader (nothing read back per frame) rather than taken on the host.
    bool device_inputs = true;
};

/// How a domain's state reaches a renderer.
enum class DrawSource {
    Device,    ///< where it was computed when that is the renderer's device, else read back
    ReadBack,  ///< always read back and uploaded (what a renderer on its own device pays)
};

/// One kind of simulated thing. Methods are called in this order: scene_instances() and
/// keep_instances() once, then open() (again after close() when "auto" falls back to the
/// cpu backend), then frames: step() with first = 0, 1, ... in order, and rewind() back to
/// frame 0. Errors name the domain's data (a bird, a chain, a file).
class KODAWARI_API Domain {
public:
    virtual ~Domain() = default;
    Domain() = default;
    Domain(const Domain&) = delete;
    Domain& operator=(const Domain&) = delete;

    /// Its name, unique in a Simulation ("birds").
    [[nodiscard]] virtual std::string_view name() const = 0;
    /// What its instances are called where a scene is cut into shards ("birds").
    [[nodiscard]] virtual std::string_view instance_noun() const { return name(); }
    /// The whole scene's instances (before keep_instances()).
    [[nodiscard]] virtual std::uint32_t scene_instances() const = 0;
    /// Keeps instances [range) only (a shard; kodawari/simulation/simulation.hpp's Shard). Called
    /// once, before open(), also with the whole range.
    virtual void keep_instances(InstanceRange range) = 0;

    /// Names of what it produces for other domains.
    [[nodiscard]] virtual std::vector<std::string> outputs() const { return {}; }
    /// Names of other domains' outputs it reads: those domains step first.
    [[nodiscard]] virtual std::vector<std::string> inputs() const { return {}; }
    /// Names of the device buffers it owns and hands out with buffer(); unique in a
    /// Simulation ("birds.poses"). The domain's header says each one's element struct.
    [[nodiscard]] virtual std::vector<std::string> buffers() const { return {}; }
    /// Where one of buffers() is now, on the vulkan backends, for the application's
    /// shaders; InvalidInput, naming the domain and the buffer, when it is not on a
    /// device now (the cpu backends, or no frame yet). The Simulation asks only for names
    /// in buffers().
    [[nodiscard]] virtual Result<VulkanBufferRange> buffer(std::string_view name) const {
        return make_error(Error::Kind::InvalidInput,
                          "domain \"" + std::string(this->name()) + "\" hands out no buffer \"" + std::string(name) + "\"");
    }

    /// Opens its backends of `setup.kind`. `producers` are the domains whose outputs it
    /// named in inputs(), in that order. An Unsupported error (a buffer the device cannot
    /// bind) lets "auto" fall back to the cpu backends.
    [[nodiscard]] virtual Result<void> open(const DomainSetup& setup, std::span<Domain* const> producers) = 0;
    /// Drops its backends (before open() again).
    virtual void close() = 0;
    /// Back to before frame 0.
    [[nodiscard]] virtual Result<void> rewind() = 0;
    /// Simulates frames [first, first + frames); `out` names channels to fill (each
    /// frames x channel elements).
    [[nodiscard]] virtual Result<void> step(std::uint32_t first, std::uint32_t frames, std::span<const ChannelOutput> out) = 0;
    /// step() of one frame (`frame`) recorded into `recording`, on the Simulation's device
    /// (with the compute layer, kodawari/vulkan/compute.hpp). On the vulkan backends it is the
    /// application's command buffer (an adopted device, kodawari/vulkan/vulkan_embed.hpp's
    /// borrow_command_buffer()): record between barriers that order the work after the
    /// application's earlier work and before its later work (docs/embedding.md,
    /// "Synchronization"), and upload per-frame input through a StagingRing of the
    /// device's frames_in_flight() slots (Recording::share()). Nothing is submitted or
    /// waited for, except what a domain documents (loading its world at frame 0). Domains
    /// that cannot record say so (Unsupported, the default).
    [[nodiscard]] virtual Result<void> record(std::uint32_t frame, compute::Recording& recording) {
        (void)frame;
        (void)recording;
        return make_error(Error::Kind::Unsupported, "domain \"" + std::string(name()) + "\" cannot record into a command buffer");
    }
    /// The channels step() can fill.
    [[nodiscard]] virtual std::vector<ChannelInfo> channels() const { return {}; }
    /// The most frames a bake should step at once (bounding what it holds per chunk),
    /// from the whole scene's instances (scene_instances()), so that every shard steps in
    /// the chunks of the whole.
    [[nodiscard]] virtual std::uint32_t max_bake_frames() const { return kMaxBakeFrames; }

    /// What it runs on ("llvmpipe (LLVM 15.0.6, 256 bits)", "2 threads"); "" when it has
    /// nothing to run.
    [[nodiscard]] virtual std::string device() const = 0;
    /// Validation messages of its backends so far.
    [[nodiscard]] virtual std::uint32_t validation_messages() const { return 0; }

    /// Tells `renderer` what it draws of this domain from now on; `shared_device`: the
    /// domain's backends run on the renderer's device.
    [[nodiscard]] virtual Result<void> show_on(render::Renderer& renderer, bool shared_device) = 0;
    /// Hands `renderer` this frame's state.
    [[nodiscard]] virtual Result<void> draw_on(render::Renderer& renderer, DrawSource source, bool shared_device) = 0;
};

/// Checks that `domains` can run together: unique names, channel and buffer names, every input
/// produced by exactly one domain, no cycle. Returns the order to step them in (indices
/// into `domains`, producers first, otherwise the given order). Errors (InvalidInput) name
/// the domain and what is wrong.
[[nodiscard]] KODAWARI_API Result<std::vector<std::size_t>> order_domains(std::span<const Domain* const> domains);

/// The scene's own domains (its flocks' birds, its characters' chains), built with every
/// random draw made, for `frames` frames, none opened. Errors: the scene's.
[[nodiscard]] KODAWARI_API Result<std::vector<std::unique_ptr<Domain>>> build_scene_domains(const Scene& scene,
                                                                                           std::uint32_t frames);

}  // namespace kodawari
