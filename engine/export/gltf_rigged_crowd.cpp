// A simulated crowd of a rigged character back into its own glTF (issue 4): the clip
// pose of every node, with the simulated chain joints put where the solver left them,
// as local transforms for RiggedGlbWriter. See RiggedCrowdExport in export.hpp.

#include <cassert>
#include <cmath>

#include <glm/gtc/matrix_transform.hpp>

#include "kodawari/export.hpp"
#include "kodawari/rods/shape.hpp"

namespace kodawari {

RiggedCrowdExport::RiggedCrowdExport(const RodScene& scene, std::uint32_t character, std::vector<std::uint32_t> instances,
                                     RiggedGlbWriter writer)
    : scene_(&scene), character_(character), instances_(std::move(instances)), writer_(std::move(writer)) {}

Result<RiggedCrowdExport> RiggedCrowdExport::create(const RodScene& scene, std::uint32_t character) {
    assert(character < scene.characters.size() && scene.characters[character].rig);
    const CharacterKinematics& k = scene.characters[character];
    const gltf::Character& ch = *k.rig;
    std::vector<std::uint32_t> instances;
    std::vector<RiggedInstance> placed;
    for (std::uint32_t c = 0; c < scene.instances.size(); ++c) {
        if (scene.instances[c].character != character) continue;
        instances.push_back(c);
        placed.push_back(RiggedInstance{scene.character_names[c], scene.instances[c].placement});
    }
    // Keys for what moves: nodes some clip animates, and every chain joint.
    std::vector<bool> animated(ch.nodes.size(), false);
    for (const gltf::Animation& clip : ch.animations) {
        for (const gltf::Channel& channel : clip.channels) animated[static_cast<std::size_t>(channel.node)] = true;
    }
    for (const std::vector<int>& nodes : k.chain_nodes) {
        for (const int n : nodes) animated[static_cast<std::size_t>(n)] = true;
    }
    auto writer = RiggedGlbWriter::create(ch.source, ch, placed, std::move(animated), scene.fps, "simulation");
    if (!writer) return writer.error();
    return RiggedCrowdExport(scene, character, std::move(instances), std::move(writer).value());
}

Result<void> RiggedCrowdExport::add_frame(std::uint32_t frame, const ChainSnapshot& snapshot) {
    const RodScene& scene = *scene_;
    const CharacterKinematics& k = scene.characters[character_];
    const gltf::Character& ch = *k.rig;
    const rods::RodWorld& world = scene.world;
    const std::size_t n = ch.nodes.size();
    translation_.resize(instances_.size() * n);
    rotation_.resize(instances_.size() * n);
    scale_.resize(instances_.size() * n);
    for (std::size_t j = 0; j < instances_.size(); ++j) {
        const std::uint32_t c = instances_[j];
        const CharacterInstance& inst = scene.instances[c];
        if (inst.clip >= 0) {
            gltf::evaluate(ch, static_cast<std::size_t>(inst.clip), scene.clip_time(c, frame), pose_);
        } else {
            pose_ = gltf::rest_pose(ch);
        }
        std::copy(pose_.translation.begin(), pose_.translation.end(), translation_.begin() + static_cast<std::ptrdiff_t>(j * n));
        std::copy(pose_.rotation.begin(), pose_.rotation.end(), rotation_.begin() + static_cast<std::ptrdiff_t>(j * n));
        std::copy(pose_.scale.begin(), pose_.scale.end(), scale_.begin() + static_cast<std::ptrdiff_t>(j * n));
        world_ = pose_.world;  // without the placement: the writer's instance root carries it
        const glm::quat unplace = glm::conjugate(inst.placement.rotation);

        for (std::size_t chain_index = 0; chain_index < k.chain_nodes.size(); ++chain_index) {
            const std::vector<int>& nodes = k.chain_nodes[chain_index];
            const rods::ChainInstance& ci = world.chains[inst.chain_begin + chain_index];
            const rods::Chain& chain = world.templ(ci).chain;
            assert(nodes.size() == chain.joint_count);
            const std::size_t base = ci.joint_begin;
            for (std::uint32_t i = 1; i < chain.joint_count; ++i) {
                // SPEC A.4's skinning output: the particle's frame, its bone turned onto
                // the segment to the next joint.
                glm::quat q = glm::normalize(snapshot.orientations[base + i]);
                if (i + 1 < chain.joint_count) {
                    const glm::vec3 d = snapshot.positions[base + i + 1] - snapshot.positions[base + i];
                    const float len = glm::length(d);
                    if (len > 1e-9f) q = glm::normalize(rods::shortest_arc(glm::normalize(q * chain.bone_axis[i]), d / len) * q);
                }
                const glm::vec3 p = unplace * (snapshot.positions[base + i] - inst.placement.position);
                q = unplace * q;
                const auto node = static_cast<std::size_t>(nodes[i]);
                const auto parent = static_cast<std::size_t>(nodes[i - 1]);
                const glm::mat4& parent_world = world_[parent];
                const glm::vec3 t = glm::vec3(glm::inverse(parent_world) * glm::vec4(p, 1.0f));
                const glm::quat r = glm::normalize(glm::conjugate(gltf::rigid_part(parent_world).rotation) * q);
                const glm::vec3 s = pose_.scale[node];
                if (!std::isfinite(t.x + t.y + t.z + r.x + r.y + r.z + r.w)) {
                    return make_error(Error::Kind::Internal, scene.chain_names[inst.chain_begin + chain_index] + ", frame " +
                                                                 std::to_string(frame) + ": joint " + std::to_string(i) +
                                                                 " is not finite");
                }
                translation_[j * n + node] = t;
                rotation_[j * n + node] = r;
                world_[node] = parent_world * glm::translate(glm::mat4(1.0f), t) * glm::mat4_cast(r) * glm::scale(glm::mat4(1.0f), s);
            }
        }
    }
    return writer_.add_frame(translation_, rotation_, scale_);
}

Result<void> RiggedCrowdExport::finish(const std::string& path) { return writer_.finish(path); }

}  // namespace kodawari
