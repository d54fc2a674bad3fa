#pragma once
/// @file
/// A bake cut into shards (issue 15): each process simulates a part of the scene's
/// instances (SimulationOptions::shard) and writes its frames to a part file; merging the
/// parts hands the whole scene's frames to the outputs, which then write the file a single
/// process writes, byte for byte. Any farm scheduler can run the shards.
///
/// A part file ("kodawari part", docs/scale-out.md): a text line `KODAWARI-PART 1`, a
/// one-line JSON header (the scene file's path and FNV-1a 64 hash, frames, shard, the
/// instance ranges, backend, kodawari version), then per chunk of frames its first frame
/// and count (uint32 each), its byte count (uint64) and the part's frames (bird poses,
/// chain joint positions and orientations; little-endian, the engine's layouts), and an
/// end mark `KODAWARI-PART-END`. Written atomically.

#include <memory>
#include <span>
#include <string>

#include "kodawari/core/api.hpp"
#include "kodawari/simulation/bake.hpp"
#include "kodawari/core/result.hpp"
#include "kodawari/simulation/simulation.hpp"

namespace kodawari {

/// The sink of a shard's bake of `sim`: its frames (every channel of its domains but the
/// diagnostics: what the `.glb` outputs need) in a part file at `path`, with its shard
/// (Simulation::shard()). `sim` is read when the sink is made.
[[nodiscard]] KODAWARI_API std::unique_ptr<BakeSink> make_part_sink(std::string path, const Simulation& sim);

/// How open_parts() finds the scene.
struct MergeOptions {
    /// The scene file to use instead of the path the parts recorded (when it moved); its
    /// bytes must still be the ones the parts were baked from.
    std::string scene;
};

/// Opens the part files of one sharded bake (any order) as the source of the whole
/// scene's frames: bake() it with the sinks a single run would use. Checks, naming the
/// file and the field: each is a part file, complete; all come from the same scene
/// (bytes unchanged since), frames, shard count and backend; every shard is there once.
/// The scene is loaded and built whole (BakeWorld as a single run has it).
[[nodiscard]] KODAWARI_API Result<std::unique_ptr<BakeSource>> open_parts(std::span<const std::string> paths,
                                                                         const MergeOptions& options = {});

}  // namespace kodawari
