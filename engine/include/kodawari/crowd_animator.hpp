#pragma once
/// @file
/// The kinematic input of a RodScene frame with the rigged characters' clips evaluated
/// by a pose backend (issue 4: crowds of skinned characters animated on the GPU, each
/// instance at its own time offset): one PoseBackend per rigged character template,
/// feeding RodScene::rigged_frame(); procedural characters are posed on the CPU as
/// RodScene::frame() does.

#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "pose_backend.hpp"
#include "rod_scene.hpp"

namespace kodawari {

/// Produces RodFrames of a RodScene, its rigged characters posed by pose backends.
class CrowdAnimator {
public:
    /// Loads every rigged character template that has instances into a pose backend of
    /// `kind`. `scene` must outlive the animator. Errors: those of make_pose_backend and
    /// PoseBackend::load.
    [[nodiscard]] static Result<CrowdAnimator> create(const RodScene& scene, BackendKind kind, const BackendOptions& options);

    /// The input of frame `index` into `out` (reusing its storage), as RodScene::frame()
    /// gives it up to the pose backend's rounding (the vulkan backend: about 1e-6 of a
    /// character's size; cpu and cpu-reference: the same bits).
    [[nodiscard]] Result<void> frame(std::uint32_t index, rods::RodFrame& out);

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
        std::unique_ptr<PoseBackend> backend;
        std::vector<std::uint32_t> instances;  // RodScene::instances indices, in backend order
        std::size_t nodes = 0;
    };
    explicit CrowdAnimator(const RodScene& scene) : scene_(&scene) {}

    const RodScene* scene_;
    std::vector<Rig> rigs_;
    std::vector<glm::mat4> world_;
    double last_pose_ms_ = 0.0;
};

}  // namespace kodawari
