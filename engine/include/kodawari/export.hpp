#pragma once
/// @file
/// Outputs of a simulation: glTF 2.0 binary files with the animation baked, and JSON
/// Lines traces (docs/trace-format.md). Both are written atomically.

#include <cstdint>
#include <memory>
#include <span>
#include <string>

#include <shared/birds.h>

#include "atomic_file.hpp"
#include "birds/world.hpp"
#include "result.hpp"
#include "rod_backend.hpp"
#include "rod_scene.hpp"

namespace kodawari {

/// Writes a `.glb`: per bird a node hierarchy of the 7 parts (a simple mesh per part,
/// shared by all birds of a wing type) and one animation with TRS channels sampled at
/// every frame. `poses` holds `frames` x birds entries, frame-major.
[[nodiscard]] Result<void> write_birds_glb(const std::string& path, const birds::BirdWorld& world,
                                           std::span<const gpu::BirdPose> poses, std::uint32_t frames);

/// Writes a `.glb` of a rod scene: per character instance its skeleton as a node
/// hierarchy and, under each chain's attachment joint, the chain's joints as a
/// hierarchy (joint i the child of joint i-1) whose bones point at the next joint
/// (SPEC A.4's skinning output); one animation with translation and rotation channels
/// on every node, one key per frame. `positions` and `orientations` hold frames x
/// scene.world.joint_count world-space entries (ChainSnapshot's), frame-major.
[[nodiscard]] Result<void> write_chains_glb(const std::string& path, const RodScene& scene, std::uint32_t frames,
                                            std::span<const glm::vec3> positions, std::span<const glm::quat> orientations);

/// What the first line of a trace says.
struct TraceHeader {
    std::string scene;
    float fps = 60.0f;
    std::uint32_t frames = 0;
    std::string backend;
};

/// Streams a JSON Lines trace: a header line, then one line per bird and frame.
class TraceWriter {
public:
    /// Opens the (temporary) file and writes the header line.
    [[nodiscard]] static Result<TraceWriter> open(const std::string& path, const TraceHeader& header);

    /// Appends the records of one frame; `poses` and `diag` hold one entry per bird.
    void write_frame(std::uint32_t frame, const birds::BirdWorld& world, std::span<const gpu::BirdPose> poses,
                     std::span<const gpu::BirdDiag> diag);

    /// Appends one chain record per chain of one frame (docs/trace-format.md): for chain
    /// c its character instance characters[c], its index chains_in_character[c] within
    /// that character, its name (names may be empty), and the snapshot's view direction,
    /// weights, rest shape, joints and orientations (world space).
    void write_chains(std::uint32_t frame, float time, const rods::RodWorld& world, std::span<const std::uint32_t> characters,
                      std::span<const std::uint32_t> chains_in_character, std::span<const std::string> names,
                      const ChainSnapshot& snapshot);

    /// Completes the file (renames it into place).
    [[nodiscard]] Result<void> finish();

private:
    explicit TraceWriter(AtomicFile file) : file_(std::move(file)) {}
    AtomicFile file_;
    std::string buffer_;
};

}  // namespace kodawari
