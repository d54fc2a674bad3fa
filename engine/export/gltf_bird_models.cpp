// The birds of a user's model (issue 14, docs/bird-models.md) in the model's own glTF:
// RiggedGlbWriter copies its meshes, materials, textures and skins once and its nodes per
// bird; here each frame's 7-part pose becomes the local transforms of the mapped bones.

#include <cmath>
#include <cstdlib>
#include <utility>

#include <glm/gtc/matrix_transform.hpp>

#include "kodawari/birds/bird_model.hpp"
#include "kodawari/export/export.hpp"

namespace kodawari {

BirdModelExport::BirdModelExport(const birds::BirdWorld& world, std::size_t model, std::string path,
                                 std::vector<std::uint32_t> birds, RiggedGlbWriter writer)
    : world_(&world), model_(model), path_(std::move(path)), birds_(std::move(birds)), writer_(std::move(writer)) {}

Result<BirdModelExport> BirdModelExport::create(const birds::BirdWorld& world, std::size_t model, const std::string& path,
                                                const GlbCompaction& compaction) {
    const birds::BirdModel& m = *world.models.at(model);
    const auto type = static_cast<std::uint32_t>(birds::kWingTypeCount + model);
    std::vector<std::uint32_t> birds;
    std::vector<RiggedInstance> instances;
    for (std::uint32_t b = 0; b < world.birds.size(); ++b) {
        if (world.birds[b].ids.y != type) continue;
        birds.push_back(b);
        // The Body's bone carries the bird's world pose, so the instance stands at the origin.
        instances.push_back(RiggedInstance{m.name + "_" + std::to_string(b), rods::Transform{}});
    }
    if (birds.empty()) return make_error(Error::Kind::InvalidInput, path + ": no bird of model " + m.name);
    std::vector<bool> animated(m.character.nodes.size(), false);
    for (const int bone : m.bones) animated[static_cast<std::size_t>(bone)] = true;
    auto writer = RiggedGlbWriter::create(m.source, m.character, instances, std::move(animated), world.fps, "flight", path,
                                          compaction);
    if (!writer) return writer.error();
    BirdModelExport out(world, model, path, std::move(birds), std::move(writer).value());
    const int parent = m.character.nodes[static_cast<std::size_t>(m.bones[KW_PART_BODY])].parent;
    if (parent >= 0) out.body_parent_inverse_ = glm::inverse(animation::rest_pose(m.character).world[static_cast<std::size_t>(parent)]);
    return out;
}

Result<void> BirdModelExport::add_frames(std::span<const gpu::BirdPose> poses) {
    const birds::BirdModel& m = *world_->models[model_];
    const animation::Character& c = m.character;
    const std::size_t count = world_->birds.size();
    const std::size_t nodes = c.nodes.size();
    if (count == 0 || poses.size() % count != 0) {
        return make_error(Error::Kind::InvalidInput, path_ + ": " + std::to_string(poses.size()) + " poses are not whole frames of " +
                                                         std::to_string(count) + " birds");
    }
    translation_.resize(birds_.size() * nodes);
    rotation_.resize(birds_.size() * nodes);
    scale_.resize(birds_.size() * nodes);
    const glm::quat body_rest = animation::rigid_part(animation::rest_pose(c).world[static_cast<std::size_t>(m.bones[KW_PART_BODY])]).rotation;
    // The tail's spread s widens the rig's Tail along its X (1 + s); a node scales along
    // its own axes, so the tail bone's axis nearest the rig's X takes it.
    const glm::vec3 width = glm::conjugate(m.axes[KW_PART_TAIL]) * glm::vec3(1.0f, 0.0f, 0.0f);
    glm::length_t width_axis = 0;
    for (glm::length_t k = 1; k < 3; ++k) {
        if (std::abs(width[k]) > std::abs(width[width_axis])) width_axis = k;
    }
    const auto tail = static_cast<std::size_t>(m.bones[KW_PART_TAIL]);
    for (std::size_t at = 0; at < poses.size(); at += count) {
        for (std::size_t i = 0; i < birds_.size(); ++i) {
            const gpu::BirdPose& pose = poses[at + birds_[i]];
            for (std::size_t n = 0; n < nodes; ++n) {
                translation_[i * nodes + n] = c.nodes[n].translation;
                rotation_[i * nodes + n] = c.nodes[n].rotation;
                scale_[i * nodes + n] = c.nodes[n].scale;
            }
            const auto quat = [](const gpu::vec4& q) { return glm::normalize(glm::quat(q.w, q.x, q.y, q.z)); };
            scale_[i * nodes + tail][width_axis] *= 1.0f + pose.position.w;
            for (std::size_t part = 0; part < birds::kPartCount; ++part) {
                const auto bone = static_cast<std::size_t>(m.bones[part]);
                if (part != KW_PART_BODY) {
                    rotation_[i * nodes + bone] = birds::model_bone_rotation(m, part, quat(pose.rotation[part]));
                    continue;
                }
                // The Body bone in the world: at the bird's position, turned by the Body's
                // world rotation from its rest orientation (the rig's and the model's axes
                // agree for the body: +Z forward, +Y up), then under its parents at rest.
                const glm::mat4 world = glm::translate(glm::mat4(1.0f), glm::vec3(pose.position.x, pose.position.y, pose.position.z)) *
                                        glm::mat4_cast(quat(pose.rotation[part]) * body_rest) * glm::scale(glm::mat4(1.0f), c.nodes[bone].scale);
                const glm::mat4 local = body_parent_inverse_ * world;
                translation_[i * nodes + bone] = glm::vec3(local[3]);
                rotation_[i * nodes + bone] = animation::rigid_part(local).rotation;
            }
        }
        KW_TRY(writer_.add_frame(translation_, rotation_, scale_));
    }
    return {};
}

Result<void> BirdModelExport::finish() { return writer_.finish(path_); }

}  // namespace kodawari
