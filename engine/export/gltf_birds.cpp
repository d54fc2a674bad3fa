// glTF 2.0 export of a bird simulation (SPEC C): one node hierarchy per bird, a small
// closed mesh per part shared by every bird of a wing type, and one animation whose
// channels hold every simulated frame.

#include <algorithm>
#include <array>
#include <cassert>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <exception>
#include <limits>
#include <new>
#include <span>
#include <ostream>
#include <streambuf>
#include <string>
#include <vector>

#include "kodawari/version.hpp"
#include "birds/bird_meshes.hpp"
#include "export/gltf_common.hpp"
#include "kodawari/birds/rig.hpp"
#include "kodawari/export.hpp"

namespace kodawari {
namespace {

using namespace gltf;

/// Adds the meshes and the material of one wing type; returns the mesh index per part.
std::array<int, birds::kPartCount> add_wing_type_meshes(tinygltf::Model& model, BufferWriter& writer,
                                                         birds::WingType type) {
    const std::size_t type_index = static_cast<std::size_t>(type);
    const std::string type_name(birds::wing_type_spec(type).name);

    tinygltf::Material material;
    material.name = type_name;
    material.pbrMetallicRoughness.baseColorFactor.assign(birds::kBirdColours[type_index].begin(),
                                                        birds::kBirdColours[type_index].end());
    material.pbrMetallicRoughness.metallicFactor = 0.0;
    material.pbrMetallicRoughness.roughnessFactor = 0.8;
    model.materials.push_back(std::move(material));
    const int material_index = static_cast<int>(model.materials.size() - 1);

    std::array<int, birds::kPartCount> mesh_indices{};
    const auto meshes = birds::bird_part_meshes(type);
    for (std::size_t part = 0; part < birds::kPartCount; ++part) {
        mesh_indices[part] = add_mesh(model, writer, meshes[part], material_index,
                                      type_name + "_" + std::string(birds::kPartNames[part]));
    }
    return mesh_indices;
}

/// Unit quaternion from a pose; a zero or non-finite input is a backend bug and is
/// reported by the caller, here it only must not divide by zero.
bool normalized(const gpu::vec4& q, Quat& out) {
    const double n = std::sqrt(static_cast<double>(q.x) * static_cast<double>(q.x) +
                               static_cast<double>(q.y) * static_cast<double>(q.y) +
                               static_cast<double>(q.z) * static_cast<double>(q.z) +
                               static_cast<double>(q.w) * static_cast<double>(q.w));
    if (!(n > 1e-12) || !std::isfinite(n)) return false;
    out = {static_cast<float>(static_cast<double>(q.x) / n), static_cast<float>(static_cast<double>(q.y) / n),
           static_cast<float>(static_cast<double>(q.z) / n), static_cast<float>(static_cast<double>(q.w) / n)};
    return true;
}


Result<void> build_and_write(AtomicFile& file, const birds::BirdWorld& world, std::span<const gpu::BirdPose> poses,
                             std::uint32_t frames) {
    const std::size_t bird_count = world.birds.size();
    tinygltf::Model model;
    model.asset.version = "2.0";
    model.asset.generator = "kodawari " + std::string(version());
    model.buffers.emplace_back();
    std::vector<unsigned char>& bytes = model.buffers[0].data;
    BufferWriter writer(bytes);

    // Meshes first, only for the wing types that occur.
    std::array<std::array<int, birds::kPartCount>, birds::kWingTypeCount> type_meshes{};
    std::array<bool, birds::kWingTypeCount> used{};
    for (std::size_t b = 0; b < bird_count; ++b) {
        const std::uint32_t type = world.birds[b].ids.y;
        if (type >= birds::kWingTypeCount) {
            return make_error(Error::Kind::InvalidInput,
                              "bird " + std::to_string(b) + " has unknown wing type " + std::to_string(type));
        }
        used[type] = true;
    }
    std::array<std::array<std::array<float, 3>, birds::kPartCount>, birds::kWingTypeCount> offsets{};
    for (std::size_t t = 0; t < birds::kWingTypeCount; ++t) {
        if (!used[t]) continue;
        type_meshes[t] = add_wing_type_meshes(model, writer, static_cast<birds::WingType>(t));
        offsets[t] = birds::part_offsets(static_cast<birds::WingType>(t));
    }

    // Animation data: the shared key times, then per bird its Body translation and the
    // rotations of its parts, each channel contiguous over the frames.
    const std::size_t time_bytes = frames * sizeof(float);
    const std::size_t translation_bytes = frames * 3 * sizeof(float);
    const std::size_t rotation_bytes = frames * 4 * sizeof(float);
    const std::size_t per_bird = translation_bytes + birds::kPartCount * rotation_bytes;
    const std::size_t animation_start = bytes.size();
    bytes.reserve(animation_start + time_bytes + bird_count * per_bird);
    writer.allocate(time_bytes + bird_count * per_bird);
    const std::size_t animation_bytes = bytes.size() - animation_start;
    const int animation_view = add_buffer_view(model, animation_start, animation_bytes, 0);

    const float fps = world.fps;
    for (std::uint32_t f = 0; f < frames; ++f) {
        const float time = static_cast<float>(f) / fps;
        std::memcpy(bytes.data() + animation_start + f * sizeof(float), &time, sizeof(float));
    }
    const int time_accessor =
        add_accessor(model, animation_view, 0, TINYGLTF_COMPONENT_TYPE_FLOAT, frames, TINYGLTF_TYPE_SCALAR);
    model.accessors[time_accessor].minValues = {0.0};
    model.accessors[time_accessor].maxValues = {static_cast<double>(static_cast<float>(frames - 1) / fps)};

    auto bird_offset = [&](std::size_t b) { return animation_start + time_bytes + b * per_bird; };
    auto translation_key = [&](std::size_t b, std::size_t f) {
        return bytes.data() + bird_offset(b) + f * sizeof(Vec3);
    };
    auto rotation_key = [&](std::size_t b, std::size_t part, std::size_t f) {
        return bytes.data() + bird_offset(b) + translation_bytes + part * rotation_bytes + f * sizeof(Quat);
    };

    // Frame-major input, channel-major output. Going through the birds in small groups,
    // all frames of a group at a time, keeps the group's 8 x kGroup output streams in
    // cache; a whole row of 12 000 birds at a time missed the cache on every key.
    constexpr std::size_t kGroup = 32;
    for (std::size_t first = 0; first < bird_count; first += kGroup) {
        const std::size_t last = std::min(first + kGroup, bird_count);
        for (std::uint32_t f = 0; f < frames; ++f) {
            const gpu::BirdPose* row = poses.data() + static_cast<std::size_t>(f) * bird_count;
            for (std::size_t b = first; b < last; ++b) {
                const gpu::BirdPose& pose = row[b];
                const Vec3 position = {pose.position.x, pose.position.y, pose.position.z};
                if (!std::isfinite(position[0]) || !std::isfinite(position[1]) || !std::isfinite(position[2])) {
                    return make_error(Error::Kind::Internal, "bird " + std::to_string(b) + ", frame " +
                                                                 std::to_string(f) + ": position is not finite");
                }
                std::memcpy(translation_key(b, f), position.data(), sizeof(Vec3));
                for (std::size_t part = 0; part < birds::kPartCount; ++part) {
                    Quat q;
                    if (!normalized(pose.rotation[part], q)) {
                        return make_error(Error::Kind::Internal,
                                          "bird " + std::to_string(b) + ", frame " + std::to_string(f) + ": " +
                                              std::string(birds::kPartNames[part]) + " rotation is not a quaternion");
                    }
                    // q and -q are the same rotation, but LINEAR (slerp) interpolation between
                    // keys in opposite hemispheres would spin the long way round.
                    if (f > 0) {
                        Quat previous;
                        std::memcpy(previous.data(), rotation_key(b, part, f - 1), sizeof(Quat));
                        const float dot =
                            previous[0] * q[0] + previous[1] * q[1] + previous[2] * q[2] + previous[3] * q[3];
                        if (dot < 0.0f) {
                            for (float& v : q) v = -v;
                        }
                    }
                    std::memcpy(rotation_key(b, part, f), q.data(), sizeof(Quat));
                }
            }
        }
    }

    // Nodes: the root, then 7 per bird (Body first, so bird b's part k is 1 + 7b + k).
    model.nodes.reserve(1 + bird_count * birds::kPartCount);
    tinygltf::Node root;
    root.name = "Birds";
    root.children.reserve(bird_count);
    model.nodes.push_back(std::move(root));
    tinygltf::Animation animation;
    animation.name = "flight";
    animation.channels.reserve(bird_count * (birds::kPartCount + 1));
    animation.samplers.reserve(bird_count * (birds::kPartCount + 1));
    model.accessors.reserve(model.accessors.size() + bird_count * (birds::kPartCount + 1));

    auto add_channel = [&](int accessor, int node, const char* path) {
        add_linear_channel(animation, time_accessor, accessor, node, path);
    };

    for (std::size_t b = 0; b < bird_count; ++b) {
        const std::uint32_t type = world.birds[b].ids.y;
        const std::string suffix = "_" + std::to_string(b);
        const int body_node = static_cast<int>(model.nodes.size());
        model.nodes[0].children.push_back(body_node);
        for (std::size_t part = 0; part < birds::kPartCount; ++part) {
            tinygltf::Node node;
            node.name = part == KW_PART_BODY ? std::string(birds::wing_type_spec(static_cast<birds::WingType>(type)).name) + suffix
                                             : std::string(birds::kPartNames[part]) + suffix;
            node.mesh = type_meshes[type][part];
            // The rest pose is frame 0, so a viewer that ignores the animation still
            // shows the flock where it starts.
            Quat q0;
            std::memcpy(q0.data(), rotation_key(b, part, 0), sizeof(Quat));
            node.rotation = {static_cast<double>(q0[0]), static_cast<double>(q0[1]), static_cast<double>(q0[2]),
                             static_cast<double>(q0[3])};
            if (part == KW_PART_BODY) {
                Vec3 t0;
                std::memcpy(t0.data(), translation_key(b, 0), sizeof(Vec3));
                node.translation = {static_cast<double>(t0[0]), static_cast<double>(t0[1]),
                                    static_cast<double>(t0[2])};
            } else {
                const auto& o = offsets[type][part];
                node.translation = {static_cast<double>(o[0]), static_cast<double>(o[1]), static_cast<double>(o[2])};
            }
            model.nodes.push_back(std::move(node));
        }
        for (std::size_t part = 1; part < birds::kPartCount; ++part) {
            const int parent = birds::kPartParents[part];
            model.nodes[body_node + parent].children.push_back(body_node + static_cast<int>(part));
        }

        const std::size_t base = bird_offset(b) - animation_start;
        const int translation = add_accessor(model, animation_view, base, TINYGLTF_COMPONENT_TYPE_FLOAT, frames,
                                             TINYGLTF_TYPE_VEC3);
        add_channel(translation, body_node, "translation");
        for (std::size_t part = 0; part < birds::kPartCount; ++part) {
            const int rotation =
                add_accessor(model, animation_view, base + translation_bytes + part * rotation_bytes,
                             TINYGLTF_COMPONENT_TYPE_FLOAT, frames, TINYGLTF_TYPE_VEC4);
            add_channel(rotation, body_node + static_cast<int>(part), "rotation");
        }
    }
    // An animation without channels is invalid glTF: a world without birds gets none.
    if (!animation.channels.empty()) model.animations.push_back(std::move(animation));

    tinygltf::Scene scene;
    scene.name = "flock";
    scene.nodes.push_back(0);
    model.scenes.push_back(std::move(scene));
    model.defaultScene = 0;

    return write_glb(file, model);
}

}  // namespace

Result<void> write_birds_glb(const std::string& path, const birds::BirdWorld& world,
                             std::span<const gpu::BirdPose> poses, std::uint32_t frames) {
    const std::size_t bird_count = world.birds.size();
    if (frames == 0) {
        return make_error(Error::Kind::InvalidInput, path + ": cannot write an animation of 0 frames");
    }
    if (poses.size() != static_cast<std::size_t>(frames) * bird_count) {
        return make_error(Error::Kind::InvalidInput,
                          path + ": expected " + std::to_string(frames) + " frames x " + std::to_string(bird_count) +
                              " birds = " + std::to_string(static_cast<std::size_t>(frames) * bird_count) +
                              " poses, got " + std::to_string(poses.size()));
    }
    if (!(world.fps > 0.0f) || !std::isfinite(world.fps)) {
        return make_error(Error::Kind::InvalidInput, path + ": fps must be positive, got " + std::to_string(world.fps));
    }
    // A GLB's length field is 32 bits.
    const double estimated = static_cast<double>(poses.size()) * static_cast<double>(3 + 4 * birds::kPartCount) * 4.0;
    if (estimated > 4.0e9) {
        return make_error(Error::Kind::InvalidInput,
                          path + ": " + std::to_string(poses.size()) + " poses exceed the 4 GiB limit of a .glb");
    }

    return write_file_atomically(path, [&](AtomicFile& file) { return build_and_write(file, world, poses, frames); });
}
}  // namespace kodawari
