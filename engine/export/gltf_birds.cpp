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
#include "export/gltf_json_stream.hpp"
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

    // The JSON's per-bird elements, made while it is written (build_and_write()).
    struct Layout;
    void root_node(std::vector<tinygltf::Node>& out) const;
    void bird_nodes(const Layout& layout, std::size_t b, std::vector<tinygltf::Node>& out) const;
    void bird_accessors(const Layout& layout, std::size_t b, std::vector<tinygltf::Accessor>& out) const;
    void bird_samplers(const Layout& layout, std::size_t b, std::vector<tinygltf::AnimationSampler>& out) const;
    void bird_channels(std::size_t b, std::vector<tinygltf::AnimationChannel>& out) const;
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
    // A GLB's length field is 32 bits. Refused here, before the simulation runs, when the
    // keys are written as they are; compacted, their size is known only once they are
    // reduced, and write_streamed_glb() refuses a buffer past 4 GiB then, before any JSON.
    const double poses = static_cast<double>(frames) * static_cast<double>(bird_count);
    if (!compaction.enabled && poses * static_cast<double>(kRecordBytes) > 4.0e9) {
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

// Where bird b's elements go, as build_and_write() laid out the model: nodes 1 + 7b + part
// (Body first), accessors first_accessor + 8b + k and the samplers and channels 8b + k of
// animation 0 (k = 0: the Body's translation, 1 + part: the part's rotation), the keys in
// the animation view at time_bytes + b x per_bird.
struct BirdGlbWriter::Impl::Layout {
    std::array<std::array<int, birds::kPartCount>, birds::kWingTypeCount> meshes{};
    std::array<std::array<std::array<float, 3>, birds::kPartCount>, birds::kWingTypeCount> offsets{};
    int animation_view = -1;
    int time_accessor = -1;
    int first_accessor = -1;
    std::size_t time_bytes = 0;
    std::size_t translation_bytes = 0;
    std::size_t rotation_bytes = 0;
    std::size_t per_bird = 0;
    // Compacted: the channels' accessors and their key times come from `compact` (the
    // buffer view `animation_view` holds its tail), bird b's from first_accessor +
    // compact->accessors_before(b) on.
    const CompactKeys* compact = nullptr;

    static constexpr std::size_t kChannels = 1 + birds::kPartCount;
    [[nodiscard]] static int body_node(std::size_t b) { return static_cast<int>(1 + b * birds::kPartCount); }
};

// The root, parent of every bird's Body.
void BirdGlbWriter::Impl::root_node(std::vector<tinygltf::Node>& out) const {
    tinygltf::Node& root = out.emplace_back();
    root.name = "Birds";
    root.children.reserve(count());
    for (std::size_t b = 0; b < count(); ++b) root.children.push_back(Layout::body_node(b));
}

void BirdGlbWriter::Impl::bird_nodes(const Layout& layout, std::size_t b, std::vector<tinygltf::Node>& out) const {
    const std::uint32_t type = world->birds[b].ids.y;
    const std::string suffix = "_" + std::to_string(b);
    const int body = Layout::body_node(b);
    const float* rest = first.data() + b * kRecordFloats;
    for (std::size_t part = 0; part < birds::kPartCount; ++part) {
        tinygltf::Node& node = out.emplace_back();
        node.name = part == KW_PART_BODY ? std::string(birds::wing_type_spec(static_cast<birds::WingType>(type)).name) + suffix
                                         : std::string(birds::kPartNames[part]) + suffix;
        node.mesh = layout.meshes[type][part];
        // The rest pose is frame 0, so a viewer that ignores the animation still shows
        // the flock where it starts.
        const float* q0 = rest + 3 + 4 * part;
        node.rotation = {static_cast<double>(q0[0]), static_cast<double>(q0[1]), static_cast<double>(q0[2]),
                         static_cast<double>(q0[3])};
        if (part == KW_PART_BODY) {
            node.translation = {static_cast<double>(rest[0]), static_cast<double>(rest[1]), static_cast<double>(rest[2])};
        } else {
            const auto& o = layout.offsets[type][part];
            node.translation = {static_cast<double>(o[0]), static_cast<double>(o[1]), static_cast<double>(o[2])};
        }
        for (std::size_t child = 1; child < birds::kPartCount; ++child) {
            if (birds::kPartParents[child] == static_cast<int>(part)) node.children.push_back(body + static_cast<int>(child));
        }
    }
}

// Bird b's keys: the Body's translations, then each part's rotations, over all frames;
// compacted, each channel's kept keys and, where not shared, their times.
void BirdGlbWriter::Impl::bird_accessors(const Layout& layout, std::size_t b, std::vector<tinygltf::Accessor>& out) const {
    if (layout.compact) {
        layout.compact->item_accessors(b, layout.animation_view, out);
        return;
    }
    const auto add = [&](std::size_t offset, int type) {
        tinygltf::Accessor& accessor = out.emplace_back();
        accessor.bufferView = layout.animation_view;
        accessor.byteOffset = offset;
        accessor.componentType = TINYGLTF_COMPONENT_TYPE_FLOAT;
        accessor.count = frames;
        accessor.type = type;
    };
    const std::size_t base = layout.time_bytes + b * layout.per_bird;
    add(base, TINYGLTF_TYPE_VEC3);
    for (std::size_t part = 0; part < birds::kPartCount; ++part) {
        add(base + layout.translation_bytes + part * layout.rotation_bytes, TINYGLTF_TYPE_VEC4);
    }
}

void BirdGlbWriter::Impl::bird_samplers(const Layout& layout, std::size_t b,
                                        std::vector<tinygltf::AnimationSampler>& out) const {
    if (layout.compact) {
        std::vector<std::pair<int, int>> io;
        layout.compact->item_channels(b, layout.first_accessor + static_cast<int>(layout.compact->accessors_before(b)), io);
        for (const auto& [input, output] : io) {
            tinygltf::AnimationSampler& sampler = out.emplace_back();
            sampler.input = input;
            sampler.output = output;
            sampler.interpolation = "LINEAR";
        }
        return;
    }
    for (std::size_t k = 0; k < Layout::kChannels; ++k) {
        tinygltf::AnimationSampler& sampler = out.emplace_back();
        sampler.input = layout.time_accessor;
        sampler.output = layout.first_accessor + static_cast<int>(b * Layout::kChannels + k);
        sampler.interpolation = "LINEAR";
    }
}

void BirdGlbWriter::Impl::bird_channels(std::size_t b, std::vector<tinygltf::AnimationChannel>& out) const {
    for (std::size_t k = 0; k < Layout::kChannels; ++k) {
        tinygltf::AnimationChannel& channel = out.emplace_back();
        channel.sampler = static_cast<int>(b * Layout::kChannels + k);
        channel.target_node = Layout::body_node(b) + static_cast<int>(k == 0 ? 0 : k - 1);
        channel.target_path = k == 0 ? "translation" : "rotation";
    }
}

// The model holds what does not grow with the flock (meshes, materials, the key times);
// the birds' nodes, accessors, channels and samplers are made one bird at a time while
// the JSON is written (write_streamed_glb), and their keys copied from the key file.
Result<void> BirdGlbWriter::Impl::build_and_write(AtomicFile& file) {
    const std::size_t bird_count = count();
    tinygltf::Model model;
    model.asset.version = "2.0";
    model.asset.generator = "kodawari " + std::string(version());
    model.buffers.emplace_back();
    std::vector<unsigned char>& bytes = model.buffers[0].data;
    BufferWriter writer(bytes);
    Layout layout;

    // Meshes first, only for the wing types that occur.
    std::array<bool, birds::kWingTypeCount> used{};
    for (std::size_t b = 0; b < bird_count; ++b) used[world->birds[b].ids.y] = true;
    for (std::size_t t = 0; t < birds::kWingTypeCount; ++t) {
        if (!used[t]) continue;
        layout.meshes[t] = add_wing_type_meshes(model, writer, static_cast<birds::WingType>(t));
        layout.offsets[t] = birds::part_offsets(static_cast<birds::WingType>(t));
    }

    // Animation data: the shared key times (in memory), then per bird its Body
    // translation and the rotations of its parts, each channel contiguous over the frames
    // (the tail, copied from the key file). Compacted (GlbCompaction), the tail is
    // CompactKeys' instead, key times included, in one buffer view after the meshes.
    layout.time_bytes = frames * sizeof(float);
    layout.translation_bytes = frames * 3 * sizeof(float);
    layout.rotation_bytes = frames * 4 * sizeof(float);
    layout.per_bird = layout.translation_bytes + birds::kPartCount * layout.rotation_bytes;
    const float fps = world->fps;
    std::optional<CompactKeys> compact;
    if (compaction.enabled) {
        std::vector<float> times(frames);
        for (std::uint32_t f = 0; f < frames; ++f) times[f] = static_cast<float>(f) / fps;
        std::array<ChannelKind, Layout::kChannels> fields{};
        fields.fill(ChannelKind::Rotation);
        fields[0] = ChannelKind::Translation;
        auto built = CompactKeys::build(keys, path, bird_count, fields, times, compaction, BirdGlbWriter::kTransposeBytes);
        if (!built) return built.error();
        compact.emplace(std::move(built).value());
        stats = compact->stats();
        layout.compact = &*compact;
        layout.animation_view = add_buffer_view(model, bytes.size(), compact->bytes(), 0);
        compact->add_shared_times(model, layout.animation_view);
        layout.first_accessor = static_cast<int>(model.accessors.size());
    }
    const std::size_t animation_start = compact ? 0 : writer.allocate(layout.time_bytes);
    if (!compact) {
        layout.animation_view =
            add_buffer_view(model, animation_start, layout.time_bytes + bird_count * layout.per_bird, 0);
        for (std::uint32_t f = 0; f < frames; ++f) {
            const float time = static_cast<float>(f) / fps;
            std::memcpy(bytes.data() + animation_start + f * sizeof(float), &time, sizeof(float));
        }
        layout.time_accessor =
            add_accessor(model, layout.animation_view, 0, TINYGLTF_COMPONENT_TYPE_FLOAT, frames, TINYGLTF_TYPE_SCALAR);
        model.accessors[layout.time_accessor].minValues = {0.0};
        model.accessors[layout.time_accessor].maxValues = {static_cast<double>(static_cast<float>(frames - 1) / fps)};
        layout.first_accessor = static_cast<int>(model.accessors.size());
    }

    StreamedElements streamed;
    // Node 0 is the root, then each bird's 7 nodes.
    streamed.nodes.groups = 1 + bird_count;
    streamed.nodes.fill = [&](std::size_t group, std::vector<tinygltf::Node>& out) {
        if (group == 0) {
            root_node(out);
        } else {
            bird_nodes(layout, group - 1, out);
        }
    };
    streamed.accessors.groups = bird_count;
    streamed.accessors.fill = [&](std::size_t b, std::vector<tinygltf::Accessor>& out) { bird_accessors(layout, b, out); };
    // An animation without channels is invalid glTF: a world without birds gets none.
    if (bird_count > 0) {
        tinygltf::Animation& animation = model.animations.emplace_back();
        animation.name = "flight";
        streamed.channels.groups = bird_count;
        streamed.channels.fill = [&](std::size_t b, std::vector<tinygltf::AnimationChannel>& out) { bird_channels(b, out); };
        streamed.samplers.groups = bird_count;
        streamed.samplers.fill = [&](std::size_t b, std::vector<tinygltf::AnimationSampler>& out) {
            bird_samplers(layout, b, out);
        };
    }

    tinygltf::Scene scene;
    scene.name = "flock";
    scene.nodes.push_back(0);
    model.scenes.push_back(std::move(scene));
    model.defaultScene = 0;

    if (compact) return write_streamed_glb(file, model, streamed, compact->bytes(), [&] { return compact->write(file); });
    return write_streamed_glb(file, model, streamed, std::uint64_t{bird_count} * layout.per_bird,
                              [&] { return copy_channels(file); });
}

Result<void> BirdGlbWriter::finish() {
    Impl& w = *impl_;
    if (w.count() > 0 && w.added != w.frames) {
        return make_error(Error::Kind::InvalidInput, w.path + ": " + std::to_string(w.added) + " of " +
                                                         std::to_string(w.frames) + " frames added");
    }
    // Only frame 0 (the rest pose) is read from here on: the last frames' rows go before
    // the copy buffers come (47 MB for 100 000 birds).
    std::vector<float>().swap(w.previous);
    std::vector<float>().swap(w.row);
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
