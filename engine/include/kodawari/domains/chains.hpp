#pragma once
/// @file
/// The chain domain (SPEC A): the characters' chains, driven by their kinematics (rigged
/// characters' clips on a PoseBackend, then the rod input), stepped on a RodBackend, as
/// one domain of a Simulation (kodawari/simulation/domain.hpp):
///
///   per frame f:  rigged characters' clips at f (pose backend)
///                 -> chain roots, reference joints, colliders, camera (RodFrame)
///                 -> f == 0: every chain at rest on its rest shape (load)
///                    f > 0:  one rod step (SPEC A.3-A.5)
///                 -> after frame 0, on one Vulkan device: the rigged characters' part of
///                    the input written on the device from then on
///
/// What is particular to chains is reached here, not through the Simulation facade.

#include <cstdint>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <string_view>

#include "kodawari/core/api.hpp"
#include "kodawari/simulation/bake.hpp"
#include "kodawari/simulation/domain.hpp"
#include "kodawari/core/result.hpp"
#include "kodawari/scene/scene.hpp"
#include "kodawari/rods/chain_snapshot.hpp"
#include "kodawari/rods/kinematics.hpp"
#include "kodawari/rods/lod.hpp"
#include "kodawari/rods/world.hpp"
#include "kodawari/vulkan/vulkan_embed.hpp"

namespace kodawari {

class Simulation;

/// The chain domain's name in a Simulation.
inline constexpr std::string_view kChainDomain = "chains";
/// Its channels (Simulation::step, the bake), each frame's ChainSnapshot arrays: per joint
/// the positions (glm::vec3), orientations (glm::quat) and blended rest shape (glm::vec3),
/// per chain the view direction (glm::vec3) and kChainWeights weights (float). The last
/// three are diagnostics (traces).
inline constexpr std::string_view kChainPositionsChannel = "chains.positions";
inline constexpr std::string_view kChainOrientationsChannel = "chains.orientations";
inline constexpr std::string_view kChainRestChannel = "chains.rest";
inline constexpr std::string_view kChainViewDirectionsChannel = "chains.view_directions";
inline constexpr std::string_view kChainWeightsChannel = "chains.weights";
// Its device buffers, the state where the vulkan backend keeps it: rod_buffers::chain_states,
// motion and spin (kodawari/backends/rod_backend.hpp), through Simulation::buffer().
inline constexpr std::uint32_t kChainWeights = rods::kMaxViewExamples + 1;

/// Time spent in the chain domain's backends. Frames 0 and 1 (loaded and put at rest,
/// then the first step, each the first dispatch of its kernels, compiled then on
/// lavapipe) are kept apart.
struct ChainTiming {
    double warmup_seconds = 0.0;  ///< frames 0 and 1
    double seconds = 0.0;         ///< wall time in the rod backend's steps from frame 2 on
    double gpu_ms = 0.0;          ///< GPU time of those steps
    double pose_ms = 0.0;         ///< the pose backends' clip evaluation (and read back)
};

/// A chain domain of `scene` (none: a scene without characters, nothing to step): what
/// build_scene_domains() makes of a scene's characters.
[[nodiscard]] KODAWARI_API std::unique_ptr<Domain> make_chain_domain(std::optional<RodScene> scene);

/// The chains and kinematics of `domain` when it is a chain domain with characters; null
/// otherwise.
[[nodiscard]] KODAWARI_API const RodScene* rod_scene_of(const Domain& domain);

/// The chains and kinematics of a bake's world; null without characters.
[[nodiscard]] KODAWARI_API const RodScene* rod_scene_of(const BakeWorld& world);
/// The chains' channels of `frames` (one frame) as a snapshot: the arrays of the channels
/// handed over, the others emptied.
KODAWARI_API void snapshot_from(const BakeFrames& frames, ChainSnapshot& out);

/// The characters as `.glb` files: the procedural characters (and then the rigged ones
/// too, as bones) in write_chains_glb's file at `path`, streamed (ChainsGlbWriter); each
/// rigged character template in its own file (RiggedCrowdExport), `path` itself when it
/// is the scene's only character, else `<path without .glb>-<character>.glb`. Its memory
/// does not grow with the frames. `compaction`: every file's keys compacted (default:
/// not).
[[nodiscard]] KODAWARI_API std::unique_ptr<BakeSink> make_chains_glb_sink(std::string path,
                                                                          const GlbCompaction& compaction = {});

/// `sim`'s characters' chains and kinematics (the part of the scene's it runs); null
/// without characters.
[[nodiscard]] KODAWARI_API const RodScene* rod_scene(const Simulation& sim);
/// The chains' state after the last step (read back from a device); nothing without chains.
[[nodiscard]] KODAWARI_API Result<void> read_chains(Simulation& sim, ChainSnapshot& out);
/// Each chain's level of detail at the last step (kodawari/rods/lod.hpp), read back with
/// the state: every chain Level::Full while the scene's `lod` is off; nothing without chains.
/// With `kept`, also whether each chain kept its state at the last step instead of stepping
/// (1; the posed and hidden levels' rate, docs/level-of-detail.md "The rate") or stepped (0).
[[nodiscard]] KODAWARI_API Result<void> read_chain_levels(Simulation& sim, std::vector<rods::Level>& out,
                                                          std::vector<std::uint8_t>* kept = nullptr);
/// The last frame's kinematic input of the chains as given to the rod backend: on one
/// Vulkan device the rigged characters' entries in it are not this frame's (they are
/// written on the device), see host_chain_input().
[[nodiscard]] KODAWARI_API const rods::RodFrame& chain_input(const Simulation& sim);
/// The last frame's kinematic input with every entry on the host (the pose matrices read
/// back when they live on a device): a sketch's root, a paused frame's colliders.
[[nodiscard]] KODAWARI_API Result<const rods::RodFrame*> host_chain_input(Simulation& sim);
/// Whether the rigged characters' rod input is written on the device.
[[nodiscard]] KODAWARI_API bool rod_inputs_on_device(const Simulation& sim);
/// The camera that drives the view-dependent rest shapes of the frames simulated from now
/// on (SPEC A.3); none: the scene's camera at each frame. A viewer's orbit camera.
KODAWARI_API void set_view_camera(Simulation& sim, std::optional<rods::Camera> camera);
/// The wind the chains feel from the next frame on, in place of the scene's `wind` (its
/// characters' own fields stay theirs); none: the scene's again. A field out of
/// range (rods::validate) is refused, naming the member. Frames already simulated keep
/// theirs; a seek or a rewind replays with the field set now.
[[nodiscard]] KODAWARI_API Result<void> set_wind(Simulation& sim, std::optional<rods::WindField> wind);
/// The budget mode (docs/level-of-detail.md "The budget"): from the next frame, the
/// characters' levels keep a frame's clips and chains within `budget_ms` (a positive
/// finite number of ms), nearest characters full first. `measured` false prices frames by
/// the scene's cost model alone (Scene::lod.costs: deterministic, as a bake must be);
/// true scales the model by what the frames measured (an interactive view's). Refused
/// (InvalidInput naming the argument) without characters, with the scene's levels of
/// detail off, or for a bad budget; Unsupported once the rigged characters' rod input is
/// written on the device (set it before the first step: the budget then keeps that input
/// on the host, where it ranks the characters).
[[nodiscard]] KODAWARI_API Result<void> set_lod_budget(Simulation& sim, float budget_ms, bool measured);
/// A budget's state: its ms, whether measured, and the scale measured frames put on the
/// cost model (1 for a model-only budget); and at the last step the depth along the camera's
/// axis within which characters could be full (the budget's cap on the full distance:
/// +infinity when it took every character the projected-size rule makes full, or before the
/// first step; -infinity when it took none) and the frame as the model priced it, ms
/// (before the scale).
struct LodBudgetState {
    float budget_ms = 0.0f;
    bool measured = false;
    float scale = 1.0f;
    float full_distance = std::numeric_limits<float>::infinity();
    double modelled_ms = 0.0;
};
/// The budget in force (the scene's `lod.budget_ms` or set_lod_budget()); none without.
[[nodiscard]] KODAWARI_API std::optional<LodBudgetState> lod_budget(const Simulation& sim);
/// The chain domain's time so far (zero without chains).
[[nodiscard]] KODAWARI_API const ChainTiming& chain_timing(const Simulation& sim);

}  // namespace kodawari
