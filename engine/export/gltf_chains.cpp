// glTF 2.0 export of a rod scene (SPEC A, C): every character instance's kinematic
// skeleton and, under each chain's attachment joint, the chain's joints as a hierarchy
// whose bones point at the next joint (the skinning rotation of SPEC A.4's output), with
// one animation holding every simulated frame.

#include <algorithm>
#include <cmath>
#include <cstring>
#include <exception>
#include <new>
#include <string>
#include <vector>

#include "kodawari/version.hpp"
#include "export/gltf_common.hpp"
#include "kodawari/export.hpp"
#include "kodawari/rods/shape.hpp"

namespace kodawari {
namespace {

using namespace gltf;

struct Local {
    glm::vec3 t;
    glm::quat r;
};

// The local transform of `child` (world) under `parent` (world).
Local relative(glm::vec3 parent_t, glm::quat parent_r, glm::vec3 child_t, glm::quat child_r) {
    const glm::quat inv = glm::conjugate(parent_r);
    return {inv * (child_t - parent_t), glm::normalize(inv * child_r)};
}

// One animated node's keys: translation then rotation, frame after frame.
struct Track {
    int node = 0;
    std::size_t offset = 0;  // of the translations in the buffer; rotations follow
};

Result<void> build_and_write(AtomicFile& file, const RodScene& scene, std::uint32_t frames,
                             std::span<const glm::vec3> positions, std::span<const glm::quat> orientations) {
    const rods::RodWorld& world = scene.world;
    tinygltf::Model model;
    model.asset.version = "2.0";
    model.asset.generator = "kodawari " + std::string(version());
    model.buffers.emplace_back();
    std::vector<unsigned char>& bytes = model.buffers[0].data;
    BufferWriter writer(bytes);

    tinygltf::Material skin;
    skin.name = "skeleton";
    skin.pbrMetallicRoughness.baseColorFactor = {0.85, 0.75, 0.65, 1.0};
    skin.pbrMetallicRoughness.metallicFactor = 0.0;
    model.materials.push_back(skin);
    tinygltf::Material hair;
    hair.name = "chain";
    hair.pbrMetallicRoughness.baseColorFactor = {0.35, 0.22, 0.12, 1.0};
    hair.pbrMetallicRoughness.metallicFactor = 0.0;
    model.materials.push_back(hair);
    const int joint_mesh = add_mesh(model, writer, box({-0.02f, -0.02f, -0.02f}, {0.02f, 0.02f, 0.02f}), 0, "joint");
    std::vector<int> chain_meshes;
    for (const rods::ChainTemplate& t : world.templates) {
        const float s = std::max(t.chain.thickness, 1e-4f);
        chain_meshes.push_back(add_mesh(model, writer, box({-s, -s, -s}, {s, s, s}), 1, t.name));
    }

    // Nodes, and the tracks that animate them.
    std::vector<Track> tracks;
    const std::size_t key_bytes = std::size_t{frames} * (sizeof(Vec3) + sizeof(Quat));
    tinygltf::Node root_node;
    root_node.name = "characters";
    model.nodes.push_back(root_node);
    auto add_node = [&](const std::string& name, int mesh, int parent) {
        tinygltf::Node node;
        node.name = name;
        node.mesh = mesh;
        model.nodes.push_back(std::move(node));
        const int index = static_cast<int>(model.nodes.size() - 1);
        model.nodes[static_cast<std::size_t>(parent)].children.push_back(index);
        tracks.push_back({index, writer.allocate(key_bytes)});
        return index;
    };
    auto write_key = [&](const Track& track, std::uint32_t f, const Local& l) {
        const Vec3 t = {l.t.x, l.t.y, l.t.z};
        Quat r = {l.r.x, l.r.y, l.r.z, l.r.w};
        unsigned char* rotations = bytes.data() + track.offset + std::size_t{frames} * sizeof(Vec3);
        if (f > 0) {
            // Consecutive keys in one hemisphere, so that players interpolate the short way.
            Quat previous;
            std::memcpy(previous.data(), rotations + (f - 1) * sizeof(Quat), sizeof(Quat));
            if (previous[0] * r[0] + previous[1] * r[1] + previous[2] * r[2] + previous[3] * r[3] < 0.0f) {
                for (float& v : r) v = -v;
            }
        }
        std::memcpy(bytes.data() + track.offset + f * sizeof(Vec3), t.data(), sizeof(Vec3));
        std::memcpy(rotations + f * sizeof(Quat), r.data(), sizeof(Quat));
    };

    std::vector<rods::Transform> joints;
    std::vector<glm::quat> bones;
    for (std::uint32_t c = 0; c < world.character_count; ++c) {
        const CharacterInstance& instance = scene.instances[c];
        const CharacterKinematics& kind = scene.characters[instance.character];
        const auto& names = scene.joint_names(c);
        const auto& parents = scene.joint_parents(c);
        // Parents first: a rigged character's joints are its glTF nodes in file order,
        // where a child may come before its parent. Tracks stay in joint order.
        std::vector<int> joint_nodes(names.size(), -1);
        std::vector<std::size_t> joint_tracks(names.size());
        for (std::size_t placed = 0; placed < names.size();) {
            for (std::size_t j = 0; j < names.size(); ++j) {
                if (joint_nodes[j] >= 0) continue;
                const int p = parents[j];
                if (p >= 0 && joint_nodes[static_cast<std::size_t>(p)] < 0) continue;
                const int parent = p < 0 ? 0 : joint_nodes[static_cast<std::size_t>(p)];
                joint_tracks[j] = tracks.size();
                joint_nodes[j] = add_node(scene.character_names[c] + "/" + names[j], joint_mesh, parent);
                ++placed;
            }
        }
        const std::uint32_t chain_count = scene.chain_count(c);
        std::vector<std::size_t> chain_tracks(chain_count);
        for (std::uint32_t k = 0; k < chain_count; ++k) {
            const std::uint32_t chain = instance.chain_begin + k;
            const rods::ChainInstance& ci = world.chains[chain];
            int parent = joint_nodes[kind.chains[k].joint];
            chain_tracks[k] = tracks.size();
            for (std::uint32_t i = 0; i < world.templ(ci).chain.joint_count; ++i) {
                parent = add_node(scene.chain_names[chain] + "/" + std::to_string(i), chain_meshes[ci.template_index], parent);
            }
        }
        for (std::uint32_t f = 0; f < frames; ++f) {
            scene.joint_poses(c, f, joints);
            for (std::size_t j = 0; j < joints.size(); ++j) {
                const Local l = parents[j] < 0 ? Local{joints[j].position, joints[j].rotation}
                                               : relative(joints[static_cast<std::size_t>(parents[j])].position,
                                                          joints[static_cast<std::size_t>(parents[j])].rotation,
                                                          joints[j].position, joints[j].rotation);
                write_key(tracks[joint_tracks[j]], f, l);
            }
            for (std::uint32_t k = 0; k < chain_count; ++k) {
                const std::uint32_t chain = instance.chain_begin + k;
                const rods::ChainInstance& ci = world.chains[chain];
                const rods::Chain& ch = world.templ(ci).chain;
                const std::size_t base = std::size_t{f} * world.joint_count + ci.joint_begin;
                // SPEC A.4 output: each bone turned so that its axis points at the next joint.
                bones.resize(ch.joint_count);
                for (std::uint32_t i = 0; i < ch.joint_count; ++i) {
                    const glm::quat q = glm::normalize(orientations[base + i]);
                    bones[i] = q;
                    if (i + 1 < ch.joint_count) {
                        const glm::vec3 d = positions[base + i + 1] - positions[base + i];
                        const float len = glm::length(d);
                        if (len > 1e-9f) bones[i] = glm::normalize(rods::shortest_arc(glm::normalize(q * ch.bone_axis[i]), d / len) * q);
                    }
                }
                const rods::Transform& attach = joints[kind.chains[k].joint];
                for (std::uint32_t i = 0; i < ch.joint_count; ++i) {
                    const Local l = i == 0 ? relative(attach.position, attach.rotation, positions[base], bones[0])
                                           : relative(positions[base + i - 1], bones[i - 1], positions[base + i], bones[i]);
                    if (!std::isfinite(l.t.x + l.t.y + l.t.z + l.r.x + l.r.y + l.r.z + l.r.w)) {
                        return make_error(Error::Kind::Internal, scene.chain_names[chain] + ", frame " + std::to_string(f) +
                                                                     ": joint " + std::to_string(i) + " is not finite");
                    }
                    write_key(tracks[chain_tracks[k] + i], f, l);
                }
            }
        }
    }

    // Times, then one sampler and two channels per track.
    std::vector<float> times(frames);
    for (std::uint32_t f = 0; f < frames; ++f) times[f] = scene.time(f);
    const std::size_t time_offset = writer.append(times.data(), times.size() * sizeof(float));
    const int time_view = add_buffer_view(model, time_offset, times.size() * sizeof(float), 0);
    const int time_accessor = add_accessor(model, time_view, 0, TINYGLTF_COMPONENT_TYPE_FLOAT, frames, TINYGLTF_TYPE_SCALAR);
    model.accessors[static_cast<std::size_t>(time_accessor)].minValues = {static_cast<double>(times.front())};
    model.accessors[static_cast<std::size_t>(time_accessor)].maxValues = {static_cast<double>(times.back())};
    tinygltf::Animation animation;
    animation.name = "simulation";
    for (const Track& track : tracks) {
        const int view = add_buffer_view(model, track.offset, key_bytes, 0);
        const int translation = add_accessor(model, view, 0, TINYGLTF_COMPONENT_TYPE_FLOAT, frames, TINYGLTF_TYPE_VEC3);
        const int rotation = add_accessor(model, view, std::size_t{frames} * sizeof(Vec3), TINYGLTF_COMPONENT_TYPE_FLOAT,
                                          frames, TINYGLTF_TYPE_VEC4);
        add_linear_channel(animation, time_accessor, translation, track.node, "translation");
        add_linear_channel(animation, time_accessor, rotation, track.node, "rotation");
        // The first frame's pose as the rest pose, for tools that show the file unanimated.
        tinygltf::Node& node = model.nodes[static_cast<std::size_t>(track.node)];
        Vec3 t;
        Quat r;
        std::memcpy(t.data(), bytes.data() + track.offset, sizeof(Vec3));
        std::memcpy(r.data(), bytes.data() + track.offset + std::size_t{frames} * sizeof(Vec3), sizeof(Quat));
        node.translation = {t[0], t[1], t[2]};
        node.rotation = {r[0], r[1], r[2], r[3]};
    }
    if (!animation.channels.empty()) model.animations.push_back(std::move(animation));

    tinygltf::Scene gltf_scene;
    gltf_scene.name = "characters";
    gltf_scene.nodes.push_back(0);
    model.scenes.push_back(std::move(gltf_scene));
    model.defaultScene = 0;
    return write_glb(file, model);
}

}  // namespace

Result<void> write_chains_glb(const std::string& path, const RodScene& scene, std::uint32_t frames,
                              std::span<const glm::vec3> positions, std::span<const glm::quat> orientations) {
    const std::size_t expected = std::size_t{frames} * scene.world.joint_count;
    if (frames == 0) return make_error(Error::Kind::InvalidInput, path + ": cannot write an animation of 0 frames");
    if (positions.size() != expected || orientations.size() != expected) {
        return make_error(Error::Kind::InvalidInput, path + ": expected " + std::to_string(expected) +
                                                         " joint positions and orientations (frames x joints), got " +
                                                         std::to_string(positions.size()) + " and " +
                                                         std::to_string(orientations.size()));
    }
    return write_file_atomically(
        path, [&](AtomicFile& file) { return build_and_write(file, scene, frames, positions, orientations); });
}

}  // namespace kodawari
