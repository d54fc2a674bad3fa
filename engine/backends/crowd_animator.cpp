// CrowdAnimator: RodScene frames with the rigged characters posed by pose backends.

#include <chrono>

#include "kodawari/crowd_animator.hpp"

namespace kodawari {

Result<CrowdAnimator> CrowdAnimator::create(const RodScene& scene, BackendKind kind, const BackendOptions& options) {
    CrowdAnimator out(scene);
    for (std::uint32_t k = 0; k < scene.characters.size(); ++k) {
        const CharacterKinematics& character = scene.characters[k];
        if (!character.rig) continue;
        Rig rig;
        rig.character = k;
        std::vector<PoseInstance> instances;
        for (std::uint32_t c = 0; c < scene.instances.size(); ++c) {
            const CharacterInstance& inst = scene.instances[c];
            if (inst.character != k) continue;
            rig.instances.push_back(c);
            instances.push_back(PoseInstance{inst.placement, inst.clip, inst.time_offset, true});
        }
        if (instances.empty()) continue;
        auto backend = make_pose_backend(kind, options);
        if (!backend) return backend.error();
        KW_TRY(backend.value()->load(*character.rig, instances));
        rig.backend = std::move(backend).value();
        rig.nodes = character.rig->nodes.size();
        out.rigs_.push_back(std::move(rig));
    }
    return out;
}

Result<void> CrowdAnimator::frame(std::uint32_t index, rods::RodFrame& out) {
    const RodScene& scene = *scene_;
    scene.kinematic_frame(index, out, /*rigged=*/rigs_.empty());
    const auto start = std::chrono::steady_clock::now();
    for (Rig& rig : rigs_) {
        KW_TRY(rig.backend->evaluate(scene.time(index)));
        KW_TRY(rig.backend->read(world_));
        for (std::size_t j = 0; j < rig.instances.size(); ++j) {
            scene.rigged_frame(rig.instances[j], std::span<const glm::mat4>(world_).subspan(j * rig.nodes, rig.nodes), out);
        }
    }
    last_pose_ms_ = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    return {};
}

std::vector<CrowdAnimator::PosedCharacter> CrowdAnimator::posed_characters() const {
    std::vector<PosedCharacter> out;
    for (const Rig& rig : rigs_) out.push_back({rig.character, rig.instances, rig.backend.get()});
    return out;
}

std::uint32_t CrowdAnimator::validation_messages() const {
    std::uint32_t n = 0;
    for (const Rig& rig : rigs_) n += rig.backend->validation_messages();
    return n;
}

}  // namespace kodawari
