#pragma once
/// @file
/// The bird domain (SPEC B): a scene's flocks, flapping and flying frame after frame on a
/// BirdBackend, as one domain of a Simulation (kodawari/simulation/domain.hpp). What is particular
/// to birds is reached here, not through the Simulation facade.

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <string_view>

#include "kodawari/core/api.hpp"
#include "kodawari/simulation/bake.hpp"
#include "kodawari/birds/world.hpp"
#include "kodawari/backends/device_data.hpp"
#include "kodawari/simulation/domain.hpp"
#include "kodawari/core/result.hpp"
#include "kodawari/vulkan/vulkan_embed.hpp"

namespace kodawari {

class Simulation;

/// The bird domain's name in a Simulation.
inline constexpr std::string_view kBirdDomain = "birds";
/// Its channels (Simulation::step, the bake): a gpu::BirdPose per bird per frame, and the
/// gpu::BirdDiag of the same frames.
inline constexpr std::string_view kBirdPosesChannel = "birds.poses";
inline constexpr std::string_view kBirdDiagChannel = "birds.diag";
// Its device buffer, the same poses where the vulkan backend keeps them:
// bird_buffers::poses (kodawari/backends/backend.hpp), through Simulation::buffer().

/// Time spent in the bird backend's own calls. The first call also compiles its kernels
/// (lavapipe compiles a pipeline at its first dispatch) and uploads the world, so it is
/// kept apart: a per-frame figure is the steady one, over what came after it.
struct BirdTiming {
    double seconds = 0.0;               ///< wall time after the first call
    std::uint64_t frames = 0;           ///< the frames of those calls
    double first_seconds = 0.0;         ///< wall time of the first call (kernels compiled)
    std::uint64_t first_frames = 0;     ///< the frames of the first call
    double first_gpu_ms = -1.0;         ///< its GPU time (< 0: none measured)
    double gpu_ms = 0.0;                ///< GPU time of the calls after the first (when every call had timestamps)
    bool gpu_timed = true;
};

/// A bird domain of `world` (its frames set): what build_scene_domains() makes of a
/// scene's flocks.
[[nodiscard]] KODAWARI_API std::unique_ptr<Domain> make_bird_domain(birds::BirdWorld world);

/// The world of `domain` when it is a bird domain; null otherwise.
[[nodiscard]] KODAWARI_API const birds::BirdWorld* bird_world_of(const Domain& domain);

/// The birds of a bake's world (an empty world when it has none).
[[nodiscard]] KODAWARI_API const birds::BirdWorld& bird_world_of(const BakeWorld& world);

/// The flock as a `.glb` (write_birds_glb()'s file) at `path`, streamed (BirdGlbWriter):
/// its memory does not grow with the frames. `compaction`: its keys compacted (default:
/// not). Each user's bird model's birds go in a glTF of their own beside it.
[[nodiscard]] KODAWARI_API std::unique_ptr<BakeSink> make_birds_glb_sink(std::string path,
                                                                         const GlbCompaction& compaction = {});

/// `sim`'s birds: the part of the scene's it runs (an empty world when it has none).
[[nodiscard]] KODAWARI_API const birds::BirdWorld& bird_world(const Simulation& sim);
/// Simulation::step with the birds' poses (and diagnostics) of every frame:
/// frames x birds each, frame-major, or empty.
[[nodiscard]] KODAWARI_API Result<void> step_birds(Simulation& sim, std::uint32_t frames, std::span<gpu::BirdPose> poses,
                                                   std::span<gpu::BirdDiag> diag = {});
/// Keep the last frame's bird poses on the host at each step (drawing them from a CPU
/// backend); on by Simulation::show_on() for backends whose poses are not on the
/// renderer's device.
KODAWARI_API void keep_bird_poses(Simulation& sim, bool keep);
/// The bird backend's time so far (zero without birds).
[[nodiscard]] KODAWARI_API const BirdTiming& bird_timing(const Simulation& sim);

}  // namespace kodawari
