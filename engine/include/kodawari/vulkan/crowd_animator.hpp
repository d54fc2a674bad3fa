#pragma once
/// @file
/// The kinematic input of a RodScene frame with the rigged characters' clips evaluated
/// by a pose backend (issue 4: crowds of skinned characters animated on the GPU, each
/// instance at its own time offset): one PoseBackend per rigged character template,
/// feeding RodScene::rigged_frame(); procedural characters are posed on the CPU as
/// RodScene::frame() does. With the vulkan pose and rod backends on one device, the rigged
/// characters' part of the input can be written there instead (write_inputs_on()), so
/// that their poses never come back to the host.

#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <vector>

#include "kodawari/core/api.hpp"
#include "kodawari/backends/pose_backend.hpp"
#include "kodawari/backends/rod_backend.hpp"
#include "kodawari/rods/lod.hpp"
#include "kodawari/rods/rod_scene.hpp"

namespace kodawari {

class DeviceInputWriter;  // engine/vulkan_backends/crowd_animator.cpp

/// Produces RodFrames of a RodScene, its rigged characters posed by pose backends.
class KODAWARI_API CrowdAnimator {
public:
    /// Loads every rigged character template that has instances into a pose backend of
    /// `kind`. `scene` must outlive the animator. Errors: those of make_pose_backend and
    /// PoseBackend::load.
    [[nodiscard]] static Result<CrowdAnimator> create(const RodScene& scene, BackendKind kind, const BackendOptions& options);

    /// The input of frame `index` into `out` (reusing its storage), as RodScene::frame()
    /// gives it up to the pose backend's rounding (the vulkan backend: about 1e-6 of a
    /// character's size; cpu and cpu-reference: the same bits).
    ///
    /// With the scene's levels of detail on (RodWorld::lod) and `out` holding frame
    /// index - 1, a rigged character whose chains keep their state this frame
    /// (rods::chain_rests on its reference joint and `out`'s camera: posed or hidden and
    /// farther than twice its full distance, or hidden far off the view, between its
    /// turns) keeps its clip's pose and its entries of `out`, so that it takes them afresh
    /// every kPosedClipPeriod frames, a hidden one every kHiddenClipPeriod, at the frames
    /// its chains step (docs/level-of-detail.md, "The rate"). With LodSettings::lower_rate
    /// off, a character posed as if twice as near keeps them between those turns while its
    /// chains step every frame. The same on every backend (the choice is made here, on the
    /// host), deterministic, and a shard's instances choose as in the whole scene
    /// (RodScene::first_instance). Not with the input written on the device
    /// (write_inputs_on()): every clip every frame there.
    [[nodiscard]] Result<void> frame(std::uint32_t index, rods::RodFrame& out);
    /// A posed character's clip every this many frames, a hidden one's every this many.
    /// The chains' rate (rods::kPosedPeriod, rods::kHiddenPeriod), so that a posed chain's
    /// turn finds its root moved on.
    static constexpr std::uint32_t kPosedClipPeriod = rods::kPosedPeriod, kHiddenClipPeriod = rods::kHiddenPeriod;
    /// Instances take those turns in groups of this many consecutive ones of the whole
    /// scene (rods::rate_turn): the cpu pose backend's batch of one clip, which it skips whole.
    static constexpr std::uint32_t kClipRateGroup = rods::kRateGroup;

    /// From now on the rigged characters' reference joints, chain roots and colliders are
    /// written on the device by shaders/rod_inputs.comp straight into `rods`'s input
    /// buffers at each of its steps (the vulkan rod backend's input writer), and frame() evaluates
    /// their clips without reading them back: those entries of its RodFrame are then not
    /// this frame's (they keep what `out` held; host_frame() gives them). Needs the vulkan
    /// pose backends and `rods` (the vulkan rod backend, loaded) on the one device of
    /// BackendOptions::context; false (nothing changed) otherwise, or without rigged
    /// characters. Frame 0 (load) still comes from frame(): load() uses it on the host.
    [[nodiscard]] Result<bool> write_inputs_on(RodBackend& rods);
    /// Whether write_inputs_on() took effect.
    [[nodiscard]] bool writes_inputs_on_device() const { return writer_ != nullptr; }
    /// The input of frame `index` with every entry on the host (the pose matrices read
    /// back) and every clip evaluated at `index`, whatever write_inputs_on() did and the
    /// clips' rate: for a viewer's paused frame (colliders to draw, a sketch's root).
    [[nodiscard]] Result<void> host_frame(std::uint32_t index, rods::RodFrame& out);

    /// Milliseconds the pose backends spent in the last frame() (evaluate + read).
    [[nodiscard]] double last_pose_ms() const { return last_pose_ms_; }
    /// Validation messages of the pose backends so far.
    [[nodiscard]] std::uint32_t validation_messages() const;

    /// A rigged character template's instances and the pose backend that evaluates them.
    struct PosedCharacter {
        std::uint32_t character;                  ///< RodScene::characters index
        std::span<const std::uint32_t> instances; ///< RodScene::instances indices, in the backend's instance order
        const PoseBackend* backend;
    };
    /// One per rigged character template with instances (valid while the animator lives).
    [[nodiscard]] std::vector<PosedCharacter> posed_characters() const;

private:
    struct Rig {
        std::uint32_t character = 0;
        std::shared_ptr<PoseBackend> backend;  // shared with the input writer
        std::vector<std::uint32_t> instances;  // RodScene::instances indices, in backend order
        std::size_t nodes = 0;
        std::vector<std::uint8_t> may_keep;    // per instance, this frame (the clips' rate)
    };
    explicit CrowdAnimator(const RodScene& scene) : scene_(&scene) {}
    Result<void> host_frame(std::uint32_t index, rods::RodFrame& out, bool clip_rate);
    // Each rig's may_keep for frame `index` from the last frame's input in `previous`;
    // false when every clip is to be evaluated (no levels of detail, a first frame, a seek).
    bool choose_clip_updates(std::uint32_t index, const rods::RodFrame& previous);

    const RodScene* scene_;
    BackendOptions options_;
    std::vector<Rig> rigs_;
    std::shared_ptr<const DeviceInputWriter> writer_;  // also held by the rod backend
    std::vector<glm::mat4> world_;
    // Threads that make the rigged characters' rod input from their matrices on the host:
    // the cpu kind's (its pipeline uses every core), one for the others, so that
    // cpu-reference stays the single-threaded yardstick.
    unsigned host_threads_ = 1;
    double last_pose_ms_ = 0.0;
    std::optional<std::uint32_t> last_rate_frame_;  // the frame choose_clip_updates() saw last
    std::vector<rods::Level> clip_level_;           // per RodScene instance, for the clips' rate
};

}  // namespace kodawari
