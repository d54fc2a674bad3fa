#pragma once
/// @file
/// The bake pipeline: a Simulation run over all its frames, each frame handed as it is
/// simulated to sinks that write outputs (glTF, traces). One loop for the `kodawari`
/// command and embedding applications; a sink decides what it keeps in memory. It knows
/// the domains through their channels alone (kodawari/simulation/domain.hpp): the sinks of the
/// scene's domains are made by the domains' headers (make_birds_glb_sink() in
/// kodawari/domains/birds.hpp, make_chains_glb_sink() and make_trace_sink() in
/// kodawari/domains/chains.hpp).

#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "kodawari/core/api.hpp"
#include "kodawari/simulation/domain.hpp"
#include "kodawari/export/export.hpp"
#include "kodawari/core/result.hpp"
#include "kodawari/scene/scene.hpp"

namespace kodawari {

class Communicator;
class Simulation;
struct ShardInfo;

/// What sinks are told before the first frame: the domains whose frames they get (a
/// Simulation's, cut to its shard when it runs one; a merge's or a distributed bake's
/// writer: the whole scene's, built with every random draw made). Sinks find theirs by
/// name (the domain headers' accessors: kodawari/domains/).
struct BakeWorld {
    const Scene* scene = nullptr;
    std::vector<const Domain*> domains;
    std::uint32_t frames = 0;  ///< frames the bake will hand over in all
    std::string backend;       ///< the backend kind's name (backend_name())
    /// The domain named `name`; null when there is none.
    [[nodiscard]] KODAWARI_API const Domain* domain(std::string_view name) const;
    /// The channel named `name` of one of the domains; none when none has it.
    [[nodiscard]] KODAWARI_API std::optional<ChannelInfo> channel(std::string_view name) const;
};

/// One channel of a domain over the frames handed over (ChannelInfo): frames x elements
/// x element_bytes bytes, frame-major.
struct BakeChannel {
    std::string name;
    std::span<const std::byte> bytes;
};

/// `count` consecutive frames from `first`, as simulated: the channels some sink asked
/// for (BakeNeeds) that a domain of the scene has.
struct BakeFrames {
    std::uint32_t first = 0;
    std::uint32_t count = 0;
    std::vector<BakeChannel> channels;
    /// The bytes of channel `name` (empty when it was not handed over).
    [[nodiscard]] KODAWARI_API std::span<const std::byte> channel(std::string_view name) const;
    /// The same as elements of T (the channel's element type; its size is asserted).
    template <class T>
    [[nodiscard]] std::span<const T> channel_as(std::string_view name) const {
        const std::span<const std::byte> bytes = channel(name);
        return {reinterpret_cast<const T*>(bytes.data()), bytes.size() / sizeof(T)};
    }
};

/// What a sink needs read back from the domains each frame: channels by name
/// (Domain::channels(); "birds.poses"). A name no domain of the scene has is handed over
/// as nothing.
struct BakeNeeds {
    std::vector<std::string> channels;
};

/// A file a sink wrote.
struct BakeOutput {
    enum class Format { Glb, Trace, Part };
    std::string path;
    Format format = Format::Glb;
    std::string description;  ///< what it holds beyond the format, for messages (may be empty)
    /// A .glb written with GlbCompaction: what compaction did.
    std::optional<GlbCompactionStats> compaction;
};

/// One output of a bake, fed frame by frame. A sink writes its files atomically: nothing
/// is left behind when a bake fails or the sink is destroyed before finish().
class KODAWARI_API BakeSink {
public:
    virtual ~BakeSink() = default;
    /// Asked once, before begin().
    [[nodiscard]] virtual BakeNeeds needs() const = 0;
    /// Called once before the first frame; errors abort the bake.
    [[nodiscard]] virtual Result<void> begin(const BakeWorld& world) = 0;
    /// Called for every frame in order, each frame once.
    [[nodiscard]] virtual Result<void> consume(const BakeFrames& frames) = 0;
    /// Completes the outputs after the last frame; returns the files written.
    [[nodiscard]] virtual Result<std::vector<BakeOutput>> finish() = 0;

    /// Distributed bakes (kodawari/simulation/distributed.hpp): whether every rank can do its own
    /// instances' part of this sink's work (a compacted birds' .glb: each rank compacts
    /// its birds' channels and writes them into the file), asked on rank 0 after begin().
    /// Then every rank makes the sink and begins it with the whole scene's world, share()
    /// tells it the rank's shard before the first frame, consume() gets that rank's own
    /// frames (its shard's instances) only, and finish_shared() replaces finish().
    [[nodiscard]] virtual bool can_share() const { return false; }
    /// The file the ranks would write into, as every rank resolves the path (a relative
    /// one from its working directory): a sink is shared only where every rank can
    /// write into that file's folder (a file system they share), checked before the
    /// first frame; elsewhere rank 0 writes it alone from the gathered frames.
    [[nodiscard]] virtual std::string share_probe() const { return {}; }
    /// See can_share(). Errors: the sink's (the default: it cannot share, Internal).
    [[nodiscard]] virtual Result<void> share(const ShardInfo& mine);
    /// finish() of a shared sink, on every rank at once (collective: every rank must
    /// return the same status). Rank 0 returns the files written, the others none.
    [[nodiscard]] virtual Result<std::vector<BakeOutput>> finish_shared(Communicator& ranks);
};

/// How bake() reports and checks.
struct BakeOptions {
    /// Called after each step with the frames done and the total.
    std::function<void(std::uint32_t done, std::uint32_t total)> progress;
    /// Called after the last frame, before the sinks finish (a failure leaves no output).
    std::function<Result<void>()> simulated;
};

/// Frames handed over per call: the fewest any of `domains` takes at once
/// (Domain::max_bake_frames(): 1 with characters' chains, read back after each frame; for
/// birds as many as keep a call at most 2^18 poses), at most kMaxBakeFrames. Every source
/// of a bake asks the whole scene's domains, so that shards and ranks step in the same
/// chunks as a single process.
[[nodiscard]] KODAWARI_API std::uint32_t bake_chunk_frames(std::span<const Domain* const> domains);

/// Where a bake's frames come from: a Simulation (bake(Simulation&, ...)), the part files
/// of a sharded bake (kodawari/simulation/shards.hpp), or the ranks of a distributed bake
/// (kodawari/simulation/distributed.hpp).
class KODAWARI_API BakeSource {
public:
    virtual ~BakeSource() = default;
    /// The whole scene's world, as sinks are told it.
    [[nodiscard]] virtual BakeWorld world() const = 0;
    /// Frames per next() (bake_chunk_frames of the scene).
    [[nodiscard]] virtual std::uint32_t chunk_frames() const = 0;
    /// The next `count` frames from `first` (called in order, each frame once), with what
    /// `needs` asks for; the spans stay valid until the next call.
    [[nodiscard]] virtual Result<BakeFrames> next(std::uint32_t first, std::uint32_t count, const BakeNeeds& needs) = 0;
};

/// Hands every frame of `source` to every sink, then finishes the sinks in order. Errors:
/// the source's and the sinks' (the first one stops the bake; sinks leave no file).
[[nodiscard]] KODAWARI_API Result<std::vector<BakeOutput>> bake(BakeSource& source, std::span<BakeSink* const> sinks,
                                                                const BakeOptions& options = {});

/// `sim`'s frames as a source (what bake(Simulation&, ...) uses): each next() steps it.
/// `sim` must outlive the source.
[[nodiscard]] KODAWARI_API std::unique_ptr<BakeSource> make_simulation_source(Simulation& sim);

/// Runs `sim` (not stepped yet) over its frame_count() frames and hands each to every
/// sink, then finishes the sinks in order, in chunks of bake_chunk_frames(). Errors: the
/// simulation's and the sinks' (the first one stops the bake).
[[nodiscard]] KODAWARI_API Result<std::vector<BakeOutput>> bake(Simulation& sim, std::span<BakeSink* const> sinks,
                                                                const BakeOptions& options = {});

/// A domain's positions channel (elements of 3 or more floats, x y z first: glm::vec3 or
/// glm::vec4) as write_points_glb()'s file at `path`, the points named `name`, keys at
/// `fps`: the glTF of any domain whose instances are points, with no writer of its own.
/// It keeps every frame until finish(). A channel the scene does not have, or of another
/// element size, is an InvalidInput error at begin() naming it.
[[nodiscard]] KODAWARI_API std::unique_ptr<BakeSink> make_points_glb_sink(std::string path, std::string channel,
                                                                          std::string name, float fps);

}  // namespace kodawari
