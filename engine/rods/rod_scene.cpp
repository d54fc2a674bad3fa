// The per-frame kinematic input of a RodScene (SPEC A.4 step 1: the root joints and the
// colliders follow the animated skeleton; SPEC A.3: the camera and the reference joints
// decide the view). Runs every frame for every character instance, so it allocates
// nothing once `out` has its sizes and poses each skeleton in a fixed-size buffer.

#include <array>
#include <cassert>
#include <cmath>
#include <span>
#include <utility>

#include <glm/gtc/matrix_transform.hpp>

#include <kodawari/animation/pose_instance.hpp>
#include <kodawari/rods/rod_scene.hpp>
#include <kodawari/rods/shape.hpp>

namespace kodawari {
namespace {

// A collider of a character template placed by its joint's pose: its points move
// rigidly, a plane's normal b only turns.
rods::Collider place(const ColliderAttachment& a, const rods::Transform& joint) {
    const glm::vec3 b = a.kind == rods::ColliderKind::Plane ? joint.rotation * a.b : joint.position + joint.rotation * a.b;
    return rods::Collider{joint.position + joint.rotation * a.a, b, a.radius, a.kind};
}

// A key source's entry of RodFrame::keys (keyed-examples.md K.1) from world poses.
rods::Transform key_entry(const KeyJoint& key, const rods::Transform& joint, const rods::Transform* parent) {
    if (key.kind == rods::KeySourceKind::Motion) return joint;
    rods::Transform out;
    out.rotation = parent != nullptr ? glm::normalize(glm::conjugate(parent->rotation) * joint.rotation) : joint.rotation;
    return out;
}

}  // namespace

float RodScene::time(std::uint32_t index) const {
    // In double, so that frame n is n / fps rounded once, not n times 1/fps rounded twice.
    return static_cast<float>(static_cast<double>(index) / static_cast<double>(fps));
}

rods::CameraPose RodScene::camera_pose(std::uint32_t index) const { return rods::camera_pose(camera, time(index)); }

rods::RodFrame RodScene::frame(std::uint32_t index) const {
    rods::RodFrame out;
    frame(index, out);
    return out;
}

void RodScene::frame(std::uint32_t index, rods::RodFrame& out) const { kinematic_frame(index, out, true); }

void RodScene::kinematic_frame(std::uint32_t index, rods::RodFrame& out, bool rigged) const {
    const float t = time(index);
    out.time = t;
    out.dt = static_cast<float>(1.0 / static_cast<double>(fps));
    out.number = index;
    out.first_character = first_instance;
    out.camera = camera_pose(index).camera();
    out.reference.resize(world.character_count);
    out.roots.resize(world.chains.size());
    out.colliders.resize(world.collider_count);
    out.keys.resize(world.key_count);
    out.centers.resize(world.center_count);
    out.winds.assign(winds.begin(), winds.end());
    std::array<rods::Transform, rods::kMaxSkeletonJoints> poses;
    animation::Pose pose;
    std::vector<glm::mat4> nodes;
    for (std::size_t i = 0; i < instances.size(); ++i) {
        const CharacterInstance& inst = instances[i];
        const CharacterKinematics& k = characters[inst.character];
        if (k.rig) {
            if (!rigged) continue;
            rig_world(static_cast<std::uint32_t>(i), index, pose, nodes);
            rigged_frame(static_cast<std::uint32_t>(i), nodes, out);
            continue;
        }
        rods::pose_skeleton(k.skeleton, k.motion, inst.placement, t + inst.time_offset, poses);
        out.reference[i] = poses[k.skeleton.reference];
        for (std::size_t c = 0; c < k.chains.size(); ++c) {
            const ChainAttachment& a = k.chains[c];
            rods::Transform root = rods::compose(poses[a.joint], a.offset);
            root.rotation = glm::normalize(root.rotation);
            out.roots[inst.chain_begin + c] = root;
            const std::uint32_t key_begin = world.chains[inst.chain_begin + c].key_begin;
            for (std::size_t s = 0; s < a.keys.size(); ++s) {
                const KeyJoint& key = a.keys[s];
                out.keys[key_begin + s] = key_entry(key, poses[key.joint], key.parent >= 0 ? &poses[key.parent] : nullptr);
            }
        }
        for (std::size_t c = 0; c < k.colliders.size(); ++c) {
            out.colliders[inst.collider_begin + c] = place(k.colliders[c], poses[k.colliders[c].joint]);
        }
        for (std::size_t c = 0; c < k.chains.size(); ++c) {
            const std::uint32_t center = world.chains[inst.chain_begin + c].center;
            if (center != rods::kNoCenter) out.centers[center] = poses[static_cast<std::size_t>(k.chains[c].center)];
        }
    }
}

std::vector<rods::Transform> RodScene::joint_poses(std::uint32_t c, std::uint32_t index) const {
    std::vector<rods::Transform> out;
    joint_poses(c, index, out);
    return out;
}

void RodScene::joint_poses(std::uint32_t c, std::uint32_t index, std::vector<rods::Transform>& out) const {
    assert(c < instances.size());
    const CharacterInstance& inst = instances[c];
    const CharacterKinematics& k = characters[inst.character];
    if (k.rig) {
        animation::Pose pose;
        std::vector<glm::mat4> nodes;
        rig_world(c, index, pose, nodes);
        out.resize(nodes.size());
        for (std::size_t n = 0; n < nodes.size(); ++n) out[n] = animation::rigid_part(nodes[n]);
        return;
    }
    out.resize(k.skeleton.joints.size());
    rods::pose_skeleton(k.skeleton, k.motion, inst.placement, time(index) + inst.time_offset, out);
}

const std::vector<std::string>& RodScene::joint_names(std::uint32_t c) const {
    assert(c < instances.size());
    return characters[instances[c].character].joint_names;
}

const std::vector<std::int32_t>& RodScene::joint_parents(std::uint32_t c) const {
    assert(c < instances.size());
    return characters[instances[c].character].joint_parents;
}

float RodScene::clip_time(std::uint32_t c, std::uint32_t index) const {
    assert(c < instances.size());
    const CharacterInstance& inst = instances[c];
    const CharacterKinematics& k = characters[inst.character];
    if (!k.rig || inst.clip < 0) return time(index) + inst.time_offset;
    // The pose backends' formula, so that the CPU and GPU paths wrap at the same frames.
    return kodawari::clip_time(k.rig->animations[static_cast<std::size_t>(inst.clip)],
                               PoseInstance{inst.placement, inst.clip, inst.time_offset, true}, time(index));
}

void RodScene::clip_pose(std::uint32_t c, std::uint32_t index, animation::Pose& pose) const {
    const CharacterInstance& inst = instances[c];
    const animation::Character& ch = *characters[inst.character].rig;
    if (inst.clip >= 0) {
        animation::evaluate(ch, static_cast<std::size_t>(inst.clip), clip_time(c, index), pose);
    } else {
        pose = animation::rest_pose(ch);
    }
}

void RodScene::rig_world(std::uint32_t c, std::uint32_t index, animation::Pose& pose, std::vector<glm::mat4>& nodes) const {
    clip_pose(c, index, pose);
    const glm::mat4 placement = placement_matrix(instances[c].placement);
    nodes.resize(pose.world.size());
    for (std::size_t n = 0; n < nodes.size(); ++n) nodes[n] = placement * pose.world[n];
}

void RodScene::rigged_world(std::uint32_t c, std::uint32_t index, std::span<const glm::vec3> positions,
                            std::span<const glm::quat> orientations, animation::Pose& pose, std::vector<glm::mat4>& out) const {
    assert(c < instances.size());
    const CharacterInstance& inst = instances[c];
    const CharacterKinematics& k = characters[inst.character];
    assert(k.rig);
    const animation::Character& ch = *k.rig;
    // The clip's local transforms; world matrices are composed once, below, with the
    // simulated joints put in on the way down.
    clip_pose(c, index, pose);
    const glm::mat4 placement = placement_matrix(inst.placement);
    out.resize(ch.nodes.size());
    for (const int n : ch.order) {
        const auto node = static_cast<std::size_t>(n);
        const animation::Node& src = ch.nodes[node];
        const glm::mat4 parent = src.parent >= 0 ? out[static_cast<std::size_t>(src.parent)] : placement;
        const auto [chain, i] = k.simulated_joint[node];
        if (chain < 0) {
            // A root's world is the clip's (a root has no parent to compose with).
            out[node] = src.parent < 0 ? placement * pose.world[node]
                                       : parent * (src.matrix ? *src.matrix
                                                              : glm::translate(glm::mat4(1.0f), pose.translation[node]) *
                                                                    glm::mat4_cast(pose.rotation[node]) *
                                                                    glm::scale(glm::mat4(1.0f), pose.scale[node]));
            continue;
        }
        const rods::ChainInstance& ci = world.chains[inst.chain_begin + static_cast<std::size_t>(chain)];
        const rods::Chain& rod = world.templ(ci).chain;
        const std::size_t base = ci.joint_begin;
        const auto j = static_cast<std::size_t>(i);
        glm::quat q = glm::normalize(orientations[base + j]);
        if (j + 1 < rod.joint_count) {
            const glm::vec3 d = positions[base + j + 1] - positions[base + j];
            const float len = glm::length(d);
            if (len > 1e-9f) q = glm::normalize(rods::shortest_arc(glm::normalize(q * rod.bone_axis[j]), d / len) * q);
        }
        out[node] = glm::translate(glm::mat4(1.0f), positions[base + j]) * glm::mat4_cast(q) *
                      glm::scale(glm::mat4(1.0f), pose.scale[node]);
    }
}

namespace {

// The rigid parts of one instance's node matrices, each node's decomposed once: its
// reference joint, chain roots, key joints, colliders and centers share nodes (a
// character's head is typically four of them), and the decomposition (three lengths, a
// determinant, a quaternion) was an eighth of a 10 000-character frame on the cpu backend.
// Same bits as calling animation::rigid_part each time.
class RigidParts {
public:
    explicit RigidParts(std::span<const glm::mat4> nodes) : nodes_(nodes) {}
    rods::Transform operator()(std::size_t node) {
        for (std::size_t i = 0; i < count_; ++i) {
            if (node_[i] == node) return part_[i];
        }
        const rods::Transform t = animation::rigid_part(nodes_[node]);
        if (count_ < node_.size()) {
            node_[count_] = node;
            part_[count_++] = t;
        }
        return t;
    }

private:
    std::span<const glm::mat4> nodes_;
    std::array<std::size_t, 24> node_{};
    std::array<rods::Transform, 24> part_{};
    std::size_t count_ = 0;
};

}  // namespace

void RodScene::rigged_frame(std::uint32_t c, std::span<const glm::mat4> nodes, rods::RodFrame& out) const {
    assert(c < instances.size());
    const CharacterInstance& inst = instances[c];
    const CharacterKinematics& k = characters[inst.character];
    assert(k.rig && nodes.size() == k.rig->nodes.size());
    RigidParts part(nodes);
    out.reference[c] = part(k.skeleton.reference);
    for (std::size_t i = 0; i < k.chains.size(); ++i) {
        out.roots[inst.chain_begin + i] = part(k.chains[i].joint);
        const std::uint32_t key_begin = world.chains[inst.chain_begin + i].key_begin;
        for (std::size_t s = 0; s < k.chains[i].keys.size(); ++s) {
            const KeyJoint& key = k.chains[i].keys[s];
            const rods::Transform parent = key.parent >= 0 ? part(static_cast<std::size_t>(key.parent)) : rods::Transform{};
            out.keys[key_begin + s] = key_entry(key, part(key.joint), key.parent >= 0 ? &parent : nullptr);
        }
    }
    for (std::size_t i = 0; i < k.colliders.size(); ++i) {
        out.colliders[inst.collider_begin + i] = place(k.colliders[i], part(k.colliders[i].joint));
    }
    for (std::size_t i = 0; i < k.chains.size(); ++i) {
        const std::uint32_t center = world.chains[inst.chain_begin + i].center;
        if (center != rods::kNoCenter) out.centers[center] = part(static_cast<std::size_t>(k.chains[i].center));
    }
}

RodScene RodScene::slice(std::uint32_t begin, std::uint32_t end) const {
    assert(begin <= end && end <= instances.size());
    RodScene out;
    out.fps = fps;
    out.frames = frames;
    out.characters = characters;
    out.camera = camera;
    out.fov_deg = fov_deg;
    out.winds = winds;
    out.world.templates = world.templates;
    out.world.wind_count = world.wind_count;
    out.world.lod = world.lod;
    out.first_instance = first_instance + begin;
    if (begin == end) return out;
    // Instances own contiguous runs of chains and colliders (build_rod_scene lays them out
    // instance by instance), so a range of instances is a range of each, rebased to 0.
    const std::uint32_t chain_first = instances[begin].chain_begin;
    const std::uint32_t collider_first = instances[begin].collider_begin;
    const std::uint32_t center_first = instances[begin].center_begin;
    std::uint32_t chain_last = chain_first;
    std::uint32_t collider_last = collider_first;
    std::uint32_t center_last = center_first;
    for (std::uint32_t c = begin; c < end; ++c) {
        CharacterInstance inst = instances[c];
        const CharacterKinematics& k = characters[inst.character];
        assert(inst.chain_begin == chain_last && inst.collider_begin == collider_last);
        chain_last = inst.chain_begin + static_cast<std::uint32_t>(k.chains.size());
        collider_last = inst.collider_begin + static_cast<std::uint32_t>(k.colliders.size());
        assert(inst.center_begin == center_last);
        for (const ChainAttachment& a : k.chains) center_last += a.center >= 0 ? 1u : 0u;
        inst.chain_begin -= chain_first;
        inst.collider_begin -= collider_first;
        inst.center_begin -= center_first;
        out.instances.push_back(inst);
        out.character_names.push_back(character_names[c]);
    }
    for (std::uint32_t k = chain_first; k < chain_last; ++k) {
        rods::ChainInstance chain = world.chains[k];
        chain.character -= begin;
        chain.collider_begin -= collider_first;
        if (chain.center != rods::kNoCenter) chain.center -= center_first;
        out.world.chains.push_back(chain);
        out.chain_names.push_back(chain_names[k]);
    }
    out.world.character_count = end - begin;
    out.world.collider_count = collider_last - collider_first;
    out.world.center_count = center_last - center_first;
    // Only recomputes joint_begin and joint_count: the ranges were checked for the whole.
    [[maybe_unused]] const auto finalized = out.world.finalize();
    assert(finalized);
    return out;
}

std::uint32_t RodScene::chain_count(std::uint32_t c) const {
    assert(c < instances.size());
    return static_cast<std::uint32_t>(characters[instances[c].character].chains.size());
}

}  // namespace kodawari
