#pragma once
/// @file
/// The bake pipeline: a Simulation run over all its frames, each frame handed as it is
/// simulated to sinks that write outputs (glTF, traces). One loop for the `kodawari`
/// command and embedding applications; a sink decides what it keeps in memory.

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include <kodawari/shared/birds.h>

#include "kodawari/api.hpp"
#include "birds/world.hpp"
#include "export.hpp"
#include "result.hpp"
#include "rod_scene.hpp"
#include "rods/chain_snapshot.hpp"
#include "scene.hpp"

namespace kodawari {

class Simulation;

/// What sinks are told before the first frame.
struct BakeWorld {
    const Scene* scene = nullptr;
    const birds::BirdWorld* birds = nullptr;  ///< the flock (maybe without birds)
    const RodScene* rods = nullptr;           ///< the characters' chains, or nullptr
    std::uint32_t frames = 0;                 ///< frames the bake will hand over in all
    std::string backend;                      ///< the backend kind's name (backend_name())
};

/// `count` consecutive frames from `first`, as simulated.
struct BakeFrames {
    std::uint32_t first = 0;
    std::uint32_t count = 0;
    /// count x birds, frame-major; empty unless a sink needs them.
    std::span<const gpu::BirdPose> bird_poses;
    std::span<const gpu::BirdDiag> bird_diag;
    /// The chains after frame `first` (count is 1 then); nullptr unless a sink needs them.
    const ChainSnapshot* chains = nullptr;
};

/// What a sink needs read back from the backends each frame.
struct BakeNeeds {
    bool bird_poses = false;
    bool bird_diag = false;
    bool chains = false;
    /// With chains: their blended rest shapes, view directions and weights too (traces);
    /// part files and ranks hand them over only when asked.
    bool chain_shapes = false;
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
};

/// How bake() reports and checks.
struct BakeOptions {
    /// Called after each step with the frames done and the total.
    std::function<void(std::uint32_t done, std::uint32_t total)> progress;
    /// Called after the last frame, before the sinks finish (a failure leaves no output).
    std::function<Result<void>()> simulated;
};

/// Frames handed over per call: with chains one (they are read back after each frame),
/// else as many as keep a call at most 2^18 bird poses (1 to 120), which bounds the memory
/// of the frames in flight. Every source of a bake uses the scene's whole counts, so that
/// shards and ranks step in the same chunks as a single process.
[[nodiscard]] KODAWARI_API std::uint32_t bake_chunk_frames(std::size_t scene_birds, bool has_chains);

/// Where a bake's frames come from: a Simulation (bake(Simulation&, ...)), the part files
/// of a sharded bake (kodawari/shards.hpp), or the ranks of a distributed bake
/// (kodawari/distributed.hpp).
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

/// The flock as a `.glb` (write_birds_glb()'s file) at `path`, streamed (BirdGlbWriter):
/// its memory does not grow with the frames. `compaction`: its keys compacted (default:
/// not).
[[nodiscard]] KODAWARI_API std::unique_ptr<BakeSink> make_birds_glb_sink(std::string path,
                                                                         const GlbCompaction& compaction = {});

/// The characters as `.glb` files: the procedural characters (and then the rigged ones
/// too, as bones) in write_chains_glb's file at `path`, streamed (ChainsGlbWriter); each
/// rigged character template in its own file (RiggedCrowdExport), `path` itself when it
/// is the scene's only character, else `<path without .glb>-<character>.glb`. Its memory
/// does not grow with the frames. `compaction`: every file's keys compacted (default:
/// not).
[[nodiscard]] KODAWARI_API std::unique_ptr<BakeSink> make_chains_glb_sink(std::string path,
                                                                          const GlbCompaction& compaction = {});

/// A JSON Lines trace (docs/trace-format.md) of birds and chains at `path`.
[[nodiscard]] KODAWARI_API std::unique_ptr<BakeSink> make_trace_sink(std::string path);

}  // namespace kodawari
