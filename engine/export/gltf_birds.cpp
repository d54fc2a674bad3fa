// glTF 2.0 export of a bird simulation (SPEC C): one node hierarchy per bird, a small
// closed mesh per part shared by every bird of a wing type, and one animation whose
// channels hold every simulated frame. Streamed (BirdGlbWriter): keys arrive frame by
// frame but glTF keeps each channel's keys together, so they wait in a temporary file.

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <exception>
#include <memory>
#include <new>
#include <optional>
#include <span>
#include <utility>
#include <string>
#include <vector>

#include "kodawari/version.hpp"
#include "birds/bird_meshes.hpp"
#include "export/compact_keys.hpp"
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


// One bird's keys of one frame: the Body translation, then the parts' rotations.
constexpr std::size_t kRecordFloats = 3 + 4 * birds::kPartCount;
constexpr std::size_t kRecordBytes = kRecordFloats * sizeof(float);

}  // namespace

struct BirdGlbWriter::Impl {
    std::string path;
    const birds::BirdWorld* world = nullptr;
    std::uint32_t frames = 0;
    std::uint32_t added = 0;
    SpillFile keys;  // frames x birds records
    std::vector<float> first;     // birds x record: frame 0, the rest pose
    std::vector<float> previous;  // birds x record: the last frame added (rotation hemispheres)
    std::vector<float> row;       // birds x record being written
    GlbCompaction compaction;
    GlbCompactionStats stats;

    [[nodiscard]] std::size_t count() const { return world->birds.size(); }
    [[nodiscard]] Result<void> add_frame(std::span<const gpu::BirdPose> poses);
    [[nodiscard]] Result<void> build_and_write(AtomicFile& file);
    [[nodiscard]] Result<void> copy_channels(AtomicFile& file);
};

BirdGlbWriter::BirdGlbWriter(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
BirdGlbWriter::BirdGlbWriter(BirdGlbWriter&& other) noexcept = default;
BirdGlbWriter& BirdGlbWriter::operator=(BirdGlbWriter&& other) noexcept = default;
BirdGlbWriter::~BirdGlbWriter() = default;

Result<BirdGlbWriter> BirdGlbWriter::create(const std::string& path, const birds::BirdWorld& world, std::uint32_t frames,
                                            const GlbCompaction& compaction) {
    const std::size_t bird_count = world.birds.size();
    KW_TRY(check_compaction(path, compaction));
    if (frames == 0) {
        return make_error(Error::Kind::InvalidInput, path + ": cannot write an animation of 0 frames");
    }
    if (!(world.fps > 0.0f) || !std::isfinite(world.fps)) {
        return make_error(Error::Kind::InvalidInput, path + ": fps must be positive, got " + std::to_string(world.fps));
    }
    // A GLB's length field is 32 bits.
    const double poses = static_cast<double>(frames) * static_cast<double>(bird_count);
    if (poses * static_cast<double>(kRecordBytes) > 4.0e9) {
        return make_error(Error::Kind::InvalidInput, path + ": " + std::to_string(std::uint64_t{frames} * bird_count) +
                                                         " poses exceed the 4 GiB limit of a .glb");
    }
    for (std::size_t b = 0; b < bird_count; ++b) {
        const std::uint32_t type = world.birds[b].ids.y;
        if (type >= birds::kWingTypeCount) {
            return make_error(Error::Kind::InvalidInput,
                              path + ": bird " + std::to_string(b) + " has unknown wing type " + std::to_string(type));
        }
    }
    auto impl = std::make_unique<Impl>();
    impl->path = path;
    impl->world = &world;
    impl->frames = frames;
    impl->compaction = compaction;
    auto keys = SpillFile::open(path);
    if (!keys) return keys.error();
    impl->keys = std::move(keys).value();
    impl->row.resize(bird_count * kRecordFloats);
    return BirdGlbWriter(std::move(impl));
}

Result<void> BirdGlbWriter::add_frames(std::span<const gpu::BirdPose> poses) {
    Impl& w = *impl_;
    const std::size_t count = w.count();
    if (count == 0) return {};  // no keys: the file holds the key times alone
    if (poses.size() % count != 0 || w.added + poses.size() / count > w.frames) {
        return make_error(Error::Kind::InvalidInput, w.path + ": " + std::to_string(poses.size()) + " poses are not whole frames of " +
                                                         std::to_string(count) + " birds within the " +
                                                         std::to_string(w.frames) + " frames announced");
    }
    for (std::size_t at = 0; at < poses.size(); at += count) KW_TRY(w.add_frame(poses.subspan(at, count)));
    return {};
}

Result<void> BirdGlbWriter::Impl::add_frame(std::span<const gpu::BirdPose> poses) {
    const std::uint32_t f = added;
    for (std::size_t b = 0; b < poses.size(); ++b) {
        const gpu::BirdPose& pose = poses[b];
        float* record = row.data() + b * kRecordFloats;
        const Vec3 position = {pose.position.x, pose.position.y, pose.position.z};
        if (!std::isfinite(position[0]) || !std::isfinite(position[1]) || !std::isfinite(position[2])) {
            return make_error(Error::Kind::Internal,
                              "bird " + std::to_string(b) + ", frame " + std::to_string(f) + ": position is not finite");
        }
        std::memcpy(record, position.data(), sizeof(Vec3));
        for (std::size_t part = 0; part < birds::kPartCount; ++part) {
            Quat q;
            if (!normalized(pose.rotation[part], q)) {
                return make_error(Error::Kind::Internal, "bird " + std::to_string(b) + ", frame " + std::to_string(f) + ": " +
                                                             std::string(birds::kPartNames[part]) +
                                                             " rotation is not a quaternion");
            }
            // q and -q are the same rotation, but LINEAR (slerp) interpolation between
            // keys in opposite hemispheres would spin the long way round.
            if (f > 0) {
                const float* p = previous.data() + b * kRecordFloats + 3 + 4 * part;
                const float dot = p[0] * q[0] + p[1] * q[1] + p[2] * q[2] + p[3] * q[3];
                if (dot < 0.0f) {
                    for (float& v : q) v = -v;
                }
            }
            std::memcpy(record + 3 + 4 * part, q.data(), sizeof(Quat));
        }
    }
    KW_TRY(keys.append(row.data(), row.size() * sizeof(float)));
    if (f == 0) first = row;
    previous.swap(row);
    row.resize(previous.size());
    ++added;
    return {};
}

// The key file holds frames x birds records; the .glb per bird its translations over all
// frames, then each part's rotations. A group of birds at a time: read its records of
// every frame (one contiguous run per frame), write its channels.
Result<void> BirdGlbWriter::Impl::copy_channels(AtomicFile& file) {
    std::array<std::size_t, 1 + birds::kPartCount> fields{};
    fields.fill(4);
    fields[0] = 3;
    return copy_item_major(keys, file, count(), frames, fields, BirdGlbWriter::kTransposeBytes);
}

Result<void> BirdGlbWriter::Impl::build_and_write(AtomicFile& file) {
    const std::size_t bird_count = count();
    tinygltf::Model model;
    model.asset.version = "2.0";
    model.asset.generator = "kodawari " + std::string(version());
    model.buffers.emplace_back();
    std::vector<unsigned char>& bytes = model.buffers[0].data;
    BufferWriter writer(bytes);

    // Meshes first, only for the wing types that occur.
    std::array<std::array<int, birds::kPartCount>, birds::kWingTypeCount> type_meshes{};
    std::array<bool, birds::kWingTypeCount> used{};
    for (std::size_t b = 0; b < bird_count; ++b) used[world->birds[b].ids.y] = true;
    std::array<std::array<std::array<float, 3>, birds::kPartCount>, birds::kWingTypeCount> offsets{};
    for (std::size_t t = 0; t < birds::kWingTypeCount; ++t) {
        if (!used[t]) continue;
        type_meshes[t] = add_wing_type_meshes(model, writer, static_cast<birds::WingType>(t));
        offsets[t] = birds::part_offsets(static_cast<birds::WingType>(t));
    }

    // Animation data: the shared key times (in memory), then per bird its Body
    // translation and the rotations of its parts, each channel contiguous over the frames
    // (the tail, copied from the key file). Compacted (GlbCompaction), the tail is
    // CompactKeys' instead, key times included, in one buffer view after the meshes.
    const std::size_t time_bytes = frames * sizeof(float);
    const std::size_t translation_bytes = frames * 3 * sizeof(float);
    const std::size_t rotation_bytes = frames * 4 * sizeof(float);
    const std::size_t per_bird = translation_bytes + birds::kPartCount * rotation_bytes;
    const float fps = world->fps;
    std::optional<CompactKeys> compact;
    int animation_view = -1;
    int time_accessor = -1;
    if (compaction.enabled) {
        std::vector<float> times(frames);
        for (std::uint32_t f = 0; f < frames; ++f) times[f] = static_cast<float>(f) / fps;
        std::array<ChannelKind, 1 + birds::kPartCount> fields{};
        fields.fill(ChannelKind::Rotation);
        fields[0] = ChannelKind::Translation;
        auto built = CompactKeys::build(keys, path, bird_count, fields, times, compaction, BirdGlbWriter::kTransposeBytes);
        if (!built) return built.error();
        compact.emplace(std::move(built).value());
        stats = compact->stats();
        animation_view = add_buffer_view(model, bytes.size(), compact->bytes(), 0);
    } else {
        const std::size_t animation_start = writer.allocate(time_bytes);
        animation_view = add_buffer_view(model, animation_start, time_bytes + bird_count * per_bird, 0);
        for (std::uint32_t f = 0; f < frames; ++f) {
            const float time = static_cast<float>(f) / fps;
            std::memcpy(bytes.data() + animation_start + f * sizeof(float), &time, sizeof(float));
        }
        time_accessor = add_accessor(model, animation_view, 0, TINYGLTF_COMPONENT_TYPE_FLOAT, frames, TINYGLTF_TYPE_SCALAR);
        model.accessors[time_accessor].minValues = {0.0};
        model.accessors[time_accessor].maxValues = {static_cast<double>(static_cast<float>(frames - 1) / fps)};
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

    for (std::size_t b = 0; b < bird_count; ++b) {
        const std::uint32_t type = world->birds[b].ids.y;
        const std::string suffix = "_" + std::to_string(b);
        const int body_node = static_cast<int>(model.nodes.size());
        const float* rest = first.data() + b * kRecordFloats;
        model.nodes[0].children.push_back(body_node);
        for (std::size_t part = 0; part < birds::kPartCount; ++part) {
            tinygltf::Node node;
            node.name = part == KW_PART_BODY ? std::string(birds::wing_type_spec(static_cast<birds::WingType>(type)).name) + suffix
                                             : std::string(birds::kPartNames[part]) + suffix;
            node.mesh = type_meshes[type][part];
            // The rest pose is frame 0, so a viewer that ignores the animation still
            // shows the flock where it starts.
            const float* q0 = rest + 3 + 4 * part;
            node.rotation = {static_cast<double>(q0[0]), static_cast<double>(q0[1]), static_cast<double>(q0[2]),
                             static_cast<double>(q0[3])};
            if (part == KW_PART_BODY) {
                node.translation = {static_cast<double>(rest[0]), static_cast<double>(rest[1]), static_cast<double>(rest[2])};
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

        if (compact) {
            const auto translation = compact->add_next_channel(model, animation_view);
            add_linear_channel(animation, translation.first, translation.second, body_node, "translation");
            for (std::size_t part = 0; part < birds::kPartCount; ++part) {
                const auto rotation = compact->add_next_channel(model, animation_view);
                add_linear_channel(animation, rotation.first, rotation.second, body_node + static_cast<int>(part), "rotation");
            }
            continue;
        }
        const std::size_t base = time_bytes + b * per_bird;
        const int translation = add_accessor(model, animation_view, base, TINYGLTF_COMPONENT_TYPE_FLOAT, frames,
                                             TINYGLTF_TYPE_VEC3);
        add_linear_channel(animation, time_accessor, translation, body_node, "translation");
        for (std::size_t part = 0; part < birds::kPartCount; ++part) {
            const int rotation = add_accessor(model, animation_view, base + translation_bytes + part * rotation_bytes,
                                              TINYGLTF_COMPONENT_TYPE_FLOAT, frames, TINYGLTF_TYPE_VEC4);
            add_linear_channel(animation, time_accessor, rotation, body_node + static_cast<int>(part), "rotation");
        }
    }
    // An animation without channels is invalid glTF: a world without birds gets none.
    if (!animation.channels.empty()) model.animations.push_back(std::move(animation));

    tinygltf::Scene scene;
    scene.name = "flock";
    scene.nodes.push_back(0);
    model.scenes.push_back(std::move(scene));
    model.defaultScene = 0;

    if (compact) return write_glb_with_tail(file, model, compact->bytes(), [&] { return compact->write(file); });
    return write_glb_with_tail(file, model, std::uint64_t{bird_count} * per_bird, [&] { return copy_channels(file); });
}

Result<void> BirdGlbWriter::finish() {
    Impl& w = *impl_;
    if (w.count() > 0 && w.added != w.frames) {
        return make_error(Error::Kind::InvalidInput, w.path + ": " + std::to_string(w.added) + " of " +
                                                         std::to_string(w.frames) + " frames added");
    }
    return write_file_atomically(w.path, [&](AtomicFile& file) { return w.build_and_write(file); });
}

const GlbCompactionStats& BirdGlbWriter::compaction_stats() const { return impl_->stats; }

Result<void> write_birds_glb(const std::string& path, const birds::BirdWorld& world,
                             std::span<const gpu::BirdPose> poses, std::uint32_t frames, const GlbCompaction& compaction) {
    const std::size_t bird_count = world.birds.size();
    if (poses.size() != static_cast<std::size_t>(frames) * bird_count) {
        return make_error(Error::Kind::InvalidInput,
                          path + ": expected " + std::to_string(frames) + " frames x " + std::to_string(bird_count) +
                              " birds = " + std::to_string(static_cast<std::size_t>(frames) * bird_count) +
                              " poses, got " + std::to_string(poses.size()));
    }
    auto writer = BirdGlbWriter::create(path, world, frames, compaction);
    if (!writer) return writer.error();
    KW_TRY(writer.value().add_frames(poses));
    return writer.value().finish();
}

}  // namespace kodawari
