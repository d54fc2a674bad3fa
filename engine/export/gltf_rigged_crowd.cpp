// A simulated crowd of a rigged character back into its own glTF (issue 4): the clip
// pose of every node, with the simulated chain joints put where the solver left them,
// as local transforms for RiggedGlbWriter. See RiggedCrowdExport in export.hpp.

#include <cassert>
#include <cmath>
#include <mutex>
#include <optional>
#include <utility>

#include "core/parallel.hpp"
#include "kodawari/export/export.hpp"

namespace kodawari {

RiggedCrowdExport::RiggedCrowdExport(const RodScene& scene, std::uint32_t character, std::vector<std::uint32_t> instances,
                                     RiggedGlbWriter writer)
    : scene_(&scene), character_(character), instances_(std::move(instances)), own_end_(instances_.size()), writer_(std::move(writer)) {}

Result<void> RiggedCrowdExport::share(std::size_t begin, std::size_t end) {
    KW_TRY(writer_.share(begin, end));
    own_begin_ = begin;
    own_end_ = end;
    return {};
}

Result<RiggedCrowdExport> RiggedCrowdExport::create(const RodScene& scene, std::uint32_t character, const std::string& output,
                                                    const GlbCompaction& compaction) {
    assert(character < scene.characters.size() && scene.characters[character].rig);
    const CharacterKinematics& k = scene.characters[character];
    const animation::Character& ch = *k.rig;
    std::vector<std::uint32_t> instances;
    std::vector<RiggedInstance> placed;
    for (std::uint32_t c = 0; c < scene.instances.size(); ++c) {
        if (scene.instances[c].character != character) continue;
        instances.push_back(c);
        placed.push_back(RiggedInstance{scene.character_names[c], scene.instances[c].placement});
    }
    // Keys for what moves: nodes some clip animates, and every chain joint.
    std::vector<bool> animated(ch.nodes.size(), false);
    for (const animation::Animation& clip : ch.animations) {
        for (const animation::Channel& channel : clip.channels) animated[static_cast<std::size_t>(channel.node)] = true;
    }
    for (const std::vector<int>& nodes : k.chain_nodes) {
        for (const int n : nodes) animated[static_cast<std::size_t>(n)] = true;
    }
    auto writer = RiggedGlbWriter::create(ch.source, ch, placed, std::move(animated), scene.fps, "simulation", output, compaction);
    if (!writer) return writer.error();
    return RiggedCrowdExport(scene, character, std::move(instances), std::move(writer).value());
}

Result<void> RiggedCrowdExport::add_frame(std::uint32_t frame, const ChainSnapshot& snapshot) {
    const RodScene& scene = *scene_;
    const CharacterKinematics& k = scene.characters[character_];
    const animation::Character& ch = *k.rig;
    const std::size_t n = ch.nodes.size();
    const std::size_t own = own_end_ - own_begin_;
    translation_.resize(own * n);
    rotation_.resize(own * n);
    scale_.resize(own * n);
    // Instances are independent and each fills only its own slice: posing them (the
    // clip's CPU evaluation, RodScene::rigged_world) is most of a frame's cost, so it
    // runs on every core. The first error in instance order wins, whatever the threads.
    std::mutex failed_lock;
    std::optional<std::pair<std::size_t, Error>> failed;
    parallel_for(own, resolve_threads(0), [&](std::size_t begin, std::size_t end) {
        animation::Pose pose;
        std::vector<glm::mat4> world;
        for (std::size_t j = begin; j < end; ++j) {
            const std::uint32_t c = instances_[own_begin_ + j];
            const CharacterInstance& inst = scene.instances[c];
            // World matrices with the simulated joints placed (RodScene::rigged_world); pose
            // is left holding the clip's local TRS, which every other node keeps.
            scene.rigged_world(c, frame, snapshot.positions, snapshot.orientations, pose, world);
            std::copy(pose.translation.begin(), pose.translation.end(), translation_.begin() + static_cast<std::ptrdiff_t>(j * n));
            std::copy(pose.rotation.begin(), pose.rotation.end(), rotation_.begin() + static_cast<std::ptrdiff_t>(j * n));
            std::copy(pose.scale.begin(), pose.scale.end(), scale_.begin() + static_cast<std::ptrdiff_t>(j * n));
            for (std::size_t chain_index = 0; chain_index < k.chain_nodes.size(); ++chain_index) {
                const std::vector<int>& nodes = k.chain_nodes[chain_index];
                for (std::size_t i = 1; i < nodes.size(); ++i) {
                    // The local transform under the parent's world matrix (simulated or animated).
                    const auto node = static_cast<std::size_t>(nodes[i]);
                    const glm::mat4& parent = world[static_cast<std::size_t>(nodes[i - 1])];
                    const glm::vec3 t = glm::vec3(glm::inverse(parent) * world[node][3]);
                    const glm::quat r = glm::normalize(glm::conjugate(animation::rigid_part(parent).rotation) *
                                                       animation::rigid_part(world[node]).rotation);
                    if (!std::isfinite(t.x + t.y + t.z + r.x + r.y + r.z + r.w)) {
                        const std::lock_guard lock(failed_lock);
                        if (!failed || failed->first > j) {
                            failed.emplace(j, Error{Error::Kind::Internal, scene.chain_names[inst.chain_begin + chain_index] +
                                                                               ", frame " + std::to_string(frame) + ": joint " +
                                                                               std::to_string(i) + " is not finite"});
                        }
                        return;
                    }
                    translation_[j * n + node] = t;
                    rotation_[j * n + node] = r;
                }
            }
        }
    });
    if (failed) return failed->second;
    return writer_.add_frame(translation_, rotation_, scale_);
}

Result<void> RiggedCrowdExport::finish(const std::string& path) { return writer_.finish(path); }

}  // namespace kodawari
