// glTF 2.0 export of a rod scene (SPEC A, C): every character instance's kinematic
// skeleton and, under each chain's attachment joint, the chain's joints as a hierarchy
// whose bones point at the next joint (the skinning rotation of SPEC A.4's output), with
// one animation holding every simulated frame. Streamed (ChainsGlbWriter): keys arrive
// frame by frame but glTF keeps each channel's keys together, so they wait in a
// temporary file.

#include <algorithm>
#include <array>
#include <cassert>
#include <cmath>
#include <cstring>
#include <optional>
#include <mutex>
#include <exception>
#include <memory>
#include <new>
#include <span>
#include <string>
#include <vector>

#include "kodawari/core/version.hpp"
#include "export/compact_keys.hpp"
#include "export/shared_glb.hpp"
#include "core/parallel.hpp"
#include "export/gltf_common.hpp"
#include "kodawari/export/export.hpp"
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

// One animated node's keys of one frame: translation, then rotation.
constexpr std::size_t kRecordFloats = 7;
constexpr std::size_t kRecordBytes = kRecordFloats * sizeof(float);

}  // namespace

struct ChainsGlbWriter::Impl {
    std::string path;
    const RodScene* scene = nullptr;
    std::uint32_t frames = 0;
    std::uint32_t added = 0;
    // Meshes and nodes are known before the first frame; the animation's accessors
    // follow them at finish(), in the order the file has always had.
    tinygltf::Model model;
    std::vector<int> track_nodes;  // per track, in buffer order
    std::vector<std::vector<std::size_t>> joint_tracks, chain_tracks;  // per character
    SpillFile keys;             // frames x tracks records
    std::vector<float> first;     // tracks x record: frame 0, the rest pose
    std::vector<float> previous;  // tracks x record: the last frame added (rotation hemispheres)
    std::vector<float> row;       // own tracks x record being written
    GlbCompaction compaction;
    GlbCompactionStats stats;
    // Per character its first track (tracks are character after character), and the
    // track count at the end. The characters whose keys this writer keeps: all, or one
    // rank's (share()), and a shared writer's keys joined with the other ranks' (rank 0,
    // while it writes: finish_shared_glb()'s).
    std::vector<std::size_t> character_tracks;
    std::size_t own_begin = 0;
    std::size_t own_end = 0;
    bool shared = false;
    CompactKeys* joined = nullptr;

    [[nodiscard]] std::size_t track_base() const { return character_tracks[own_begin]; }
    [[nodiscard]] std::size_t own_tracks() const { return character_tracks[own_end] - character_tracks[own_begin]; }
    [[nodiscard]] Result<CompactKeys> compact_own();

    [[nodiscard]] std::size_t key_bytes() const { return std::size_t{frames} * kRecordBytes; }
    void build_nodes();
    [[nodiscard]] Result<void> add_frame(std::span<const glm::vec3> positions, std::span<const glm::quat> orientations);
    [[nodiscard]] Result<void> build_and_write(AtomicFile& file);
    [[nodiscard]] Result<void> copy_channels(AtomicFile& file);
    [[nodiscard]] Result<void> build_and_write_compact(AtomicFile& file);
    void add_scene();
    void set_rest_pose(std::size_t track, int node_index);
};

void ChainsGlbWriter::Impl::build_nodes() {
    const rods::RodWorld& world = scene->world;
    model.asset.version = "2.0";
    model.asset.generator = "kodawari " + std::string(version());
    model.buffers.emplace_back();
    BufferWriter writer(model.buffers[0].data);

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
        track_nodes.push_back(index);
        return index;
    };
    joint_tracks.resize(world.character_count);
    chain_tracks.resize(world.character_count);
    for (std::uint32_t c = 0; c < world.character_count; ++c) {
        character_tracks.push_back(track_nodes.size());
        const CharacterInstance& instance = scene->instances[c];
        const CharacterKinematics& kind = scene->characters[instance.character];
        const auto& names = scene->joint_names(c);
        const auto& parents = scene->joint_parents(c);
        // Parents first: a rigged character's joints are its glTF nodes in file order,
        // where a child may come before its parent. Tracks stay in joint order.
        std::vector<int> joint_nodes(names.size(), -1);
        joint_tracks[c].resize(names.size());
        for (std::size_t placed = 0; placed < names.size();) {
            for (std::size_t j = 0; j < names.size(); ++j) {
                if (joint_nodes[j] >= 0) continue;
                const int p = parents[j];
                if (p >= 0 && joint_nodes[static_cast<std::size_t>(p)] < 0) continue;
                const int parent = p < 0 ? 0 : joint_nodes[static_cast<std::size_t>(p)];
                joint_tracks[c][j] = track_nodes.size();
                joint_nodes[j] = add_node(scene->character_names[c] + "/" + names[j], joint_mesh, parent);
                ++placed;
            }
        }
        const std::uint32_t chain_count = scene->chain_count(c);
        chain_tracks[c].resize(chain_count);
        for (std::uint32_t k = 0; k < chain_count; ++k) {
            const std::uint32_t chain = instance.chain_begin + k;
            const rods::ChainInstance& ci = world.chains[chain];
            int parent = joint_nodes[kind.chains[k].joint];
            chain_tracks[c][k] = track_nodes.size();
            for (std::uint32_t i = 0; i < world.templ(ci).chain.joint_count; ++i) {
                parent = add_node(scene->chain_names[chain] + "/" + std::to_string(i), chain_meshes[ci.template_index], parent);
            }
        }
    }
    character_tracks.push_back(track_nodes.size());
    own_end = world.character_count;
}

ChainsGlbWriter::ChainsGlbWriter(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
ChainsGlbWriter::ChainsGlbWriter(ChainsGlbWriter&& other) noexcept = default;
ChainsGlbWriter& ChainsGlbWriter::operator=(ChainsGlbWriter&& other) noexcept = default;
ChainsGlbWriter::~ChainsGlbWriter() = default;

Result<ChainsGlbWriter> ChainsGlbWriter::create(const std::string& path, const RodScene& scene, std::uint32_t frames,
                                                const GlbCompaction& compaction) {
    if (frames == 0) return make_error(Error::Kind::InvalidInput, path + ": cannot write an animation of 0 frames");
    KW_TRY(check_compaction(path, compaction));
    auto impl = std::make_unique<Impl>();
    impl->compaction = compaction;
    impl->path = path;
    impl->scene = &scene;
    impl->frames = frames;
    impl->build_nodes();
    // Refused here rather than after the whole simulation has run: a GLB's length field
    // is 32 bits. The JSON is not counted yet; write_glb_with_tail checks the exact total.
    // Compacted, the keys' size is known only once they are reduced: write_glb_with_tail
    // refuses then, before writing.
    const std::uint64_t bytes = impl->model.buffers[0].data.size() +
                                impl->track_nodes.size() * (std::uint64_t{frames} * kRecordBytes) +
                                std::uint64_t{frames} * sizeof(float);
    if (!compaction.enabled && bytes > 0xFFFFFFFFull) {
        return make_error(Error::Kind::InvalidInput, path + ": " + std::to_string(impl->track_nodes.size()) + " nodes x " +
                                                         std::to_string(frames) + " frames need " + std::to_string(bytes) +
                                                         " bytes, past the 4 GiB limit of a .glb; bake fewer frames");
    }
    auto keys = SpillFile::open(path);
    if (!keys) return keys.error();
    impl->keys = std::move(keys).value();
    impl->row.resize(impl->track_nodes.size() * kRecordFloats);
    return ChainsGlbWriter(std::move(impl));
}

Result<void> ChainsGlbWriter::add_frame(std::span<const glm::vec3> positions, std::span<const glm::quat> orientations) {
    Impl& w = *impl_;
    const std::size_t joints = w.scene->world.joint_count;
    if (positions.size() != joints || orientations.size() != joints || w.added >= w.frames) {
        return make_error(Error::Kind::InvalidInput, w.path + ": frame " + std::to_string(w.added) + " of " +
                                                         std::to_string(w.frames) + " announced, with " +
                                                         std::to_string(positions.size()) + " positions and " +
                                                         std::to_string(orientations.size()) + " orientations for " +
                                                         std::to_string(joints) + " joints");
    }
    return w.add_frame(positions, orientations);
}

Result<void> ChainsGlbWriter::Impl::add_frame(std::span<const glm::vec3> positions, std::span<const glm::quat> orientations) {
    const rods::RodWorld& world = scene->world;
    const std::uint32_t f = added;
    // Rows of the own tracks only (a shared writer's: its characters').
    const std::size_t base_track = track_base();
    auto write_key = [&](std::size_t track, const Local& l) {
        track -= base_track;
        float* record = row.data() + track * kRecordFloats;
        Quat r = {l.r.x, l.r.y, l.r.z, l.r.w};
        if (f > 0) {
            // Consecutive keys in one hemisphere, so that players interpolate the short way.
            const float* p = previous.data() + track * kRecordFloats + 3;
            if (p[0] * r[0] + p[1] * r[1] + p[2] * r[2] + p[3] * r[3] < 0.0f) {
                for (float& v : r) v = -v;
            }
        }
        const Vec3 t = {l.t.x, l.t.y, l.t.z};
        std::memcpy(record, t.data(), sizeof(Vec3));
        std::memcpy(record + 3, r.data(), sizeof(Quat));
    };
    // Characters are independent and each writes only its own tracks' rows: posing their
    // skeletons (CPU kinematics) is most of a frame's cost, so it runs on every core.
    // The first error in character order wins, whatever the threads.
    std::mutex failed_lock;
    std::optional<std::pair<std::uint32_t, Error>> failed;
    parallel_for(own_end - own_begin, resolve_threads(0), [&](std::size_t begin, std::size_t end) {
        std::vector<rods::Transform> joints;
        std::vector<glm::quat> bones;
        for (auto c = static_cast<std::uint32_t>(own_begin + begin); c < own_begin + end; ++c) {
            const CharacterInstance& instance = scene->instances[c];
            const CharacterKinematics& kind = scene->characters[instance.character];
            const auto& parents = scene->joint_parents(c);
            scene->joint_poses(c, f, joints);
            for (std::size_t j = 0; j < joints.size(); ++j) {
                const Local l = parents[j] < 0 ? Local{joints[j].position, joints[j].rotation}
                                               : relative(joints[static_cast<std::size_t>(parents[j])].position,
                                                          joints[static_cast<std::size_t>(parents[j])].rotation,
                                                          joints[j].position, joints[j].rotation);
                write_key(joint_tracks[c][j], l);
            }
            const std::uint32_t chain_count = scene->chain_count(c);
            for (std::uint32_t k = 0; k < chain_count; ++k) {
                const std::uint32_t chain = instance.chain_begin + k;
                const rods::ChainInstance& ci = world.chains[chain];
                const rods::Chain& ch = world.templ(ci).chain;
                const std::size_t base = ci.joint_begin;
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
                        const std::lock_guard lock(failed_lock);
                        if (!failed || failed->first > c) {
                            failed.emplace(c, Error{Error::Kind::Internal, path + ": " + scene->chain_names[chain] + ", frame " +
                                                                              std::to_string(f) + ": joint " +
                                                                              std::to_string(i) + " is not finite"});
                        }
                        return;
                    }
                    write_key(chain_tracks[c][k] + i, l);
                }
            }
        }
    });
    if (failed) return failed->second;
    KW_TRY(keys.append(row.data(), row.size() * sizeof(float)));
    if (f == 0) {
        first.resize(track_nodes.size() * kRecordFloats);
        std::copy(row.begin(), row.end(), first.begin() + static_cast<std::ptrdiff_t>(base_track * kRecordFloats));
    }
    previous.swap(row);
    row.resize(previous.size());
    ++added;
    return {};
}

// The key file holds frames x tracks records; the .glb per track its translations over
// all frames, then its rotations, then the key times. A group of tracks at a time: read
// its records of every frame (one contiguous run per frame), write its channels.
Result<void> ChainsGlbWriter::Impl::copy_channels(AtomicFile& file) {
    constexpr std::array<std::size_t, 2> kFields = {3, 4};
    KW_TRY(copy_item_major(keys, file, track_nodes.size(), frames, kFields, ChainsGlbWriter::kTransposeBytes));
    std::vector<float> times(frames);
    for (std::uint32_t f = 0; f < frames; ++f) times[f] = scene->time(f);
    file.write(times.data(), times.size() * sizeof(float));
    return {};
}

Result<void> ChainsGlbWriter::Impl::build_and_write(AtomicFile& file) {
    // The buffer: meshes (in memory), then each track's keys, then the key times (the
    // tail, streamed by copy_channels).
    const std::size_t head = model.buffers[0].data.size();
    const std::size_t keys_bytes = track_nodes.size() * key_bytes();
    const std::size_t time_bytes = std::size_t{frames} * sizeof(float);
    const int time_view = add_buffer_view(model, head + keys_bytes, time_bytes, 0);
    const int time_accessor = add_accessor(model, time_view, 0, TINYGLTF_COMPONENT_TYPE_FLOAT, frames, TINYGLTF_TYPE_SCALAR);
    model.accessors[static_cast<std::size_t>(time_accessor)].minValues = {static_cast<double>(scene->time(0))};
    model.accessors[static_cast<std::size_t>(time_accessor)].maxValues = {static_cast<double>(scene->time(frames - 1))};
    tinygltf::Animation animation;
    animation.name = "simulation";
    for (std::size_t t = 0; t < track_nodes.size(); ++t) {
        const int node_index = track_nodes[t];
        const int view = add_buffer_view(model, head + t * key_bytes(), key_bytes(), 0);
        const int translation = add_accessor(model, view, 0, TINYGLTF_COMPONENT_TYPE_FLOAT, frames, TINYGLTF_TYPE_VEC3);
        const int rotation = add_accessor(model, view, std::size_t{frames} * sizeof(Vec3), TINYGLTF_COMPONENT_TYPE_FLOAT,
                                          frames, TINYGLTF_TYPE_VEC4);
        add_linear_channel(animation, time_accessor, translation, node_index, "translation");
        add_linear_channel(animation, time_accessor, rotation, node_index, "rotation");
        set_rest_pose(t, node_index);
    }
    if (!animation.channels.empty()) model.animations.push_back(std::move(animation));
    add_scene();
    return write_glb_with_tail(file, model, keys_bytes + time_bytes, [&] { return copy_channels(file); });
}

// The first frame's pose as the rest pose, for tools that show the file unanimated.
void ChainsGlbWriter::Impl::set_rest_pose(std::size_t track, int node_index) {
    tinygltf::Node& node = model.nodes[static_cast<std::size_t>(node_index)];
    const float* rest = first.data() + track * kRecordFloats;
    node.translation = {rest[0], rest[1], rest[2]};
    node.rotation = {rest[3], rest[4], rest[5], rest[6]};
}

void ChainsGlbWriter::Impl::add_scene() {
    tinygltf::Scene gltf_scene;
    gltf_scene.name = "characters";
    gltf_scene.nodes.push_back(0);
    model.scenes.push_back(std::move(gltf_scene));
    model.defaultScene = 0;
}

// GlbCompaction: the keys are reduced first (compact_keys.hpp), into a second temporary
// file whose bytes, after the meshes, are the buffer's tail: one buffer view holds them,
// and each channel's key times and values are accessors into it.
Result<CompactKeys> ChainsGlbWriter::Impl::compact_own() {
    std::vector<float> times(frames);
    for (std::uint32_t f = 0; f < frames; ++f) times[f] = scene->time(f);
    constexpr std::array<ChannelKind, 2> kFields = {ChannelKind::Translation, ChannelKind::Rotation};
    return CompactKeys::build(keys, path, own_tracks(), kFields, times, compaction, ChainsGlbWriter::kTransposeBytes);
}

Result<void> ChainsGlbWriter::Impl::build_and_write_compact(AtomicFile& file) {
    std::optional<Result<CompactKeys>> built_here;
    if (joined == nullptr) {
        built_here.emplace(compact_own());
        if (!*built_here) return built_here->error();
    }
    CompactKeys& keys_out = joined != nullptr ? *joined : built_here->value();
    stats = keys_out.stats();
    MeshoptJson meshopt;
    const int view = keys_out.add_views(model, model.buffers[0].data.size(), meshopt);
    tinygltf::Animation animation;
    animation.name = "simulation";
    for (std::size_t t = 0; t < track_nodes.size(); ++t) {
        const int node_index = track_nodes[t];
        const auto translation = keys_out.add_next_channel(model, view);
        add_linear_channel(animation, translation.first, translation.second, node_index, "translation");
        const auto rotation = keys_out.add_next_channel(model, view);
        add_linear_channel(animation, rotation.first, rotation.second, node_index, "rotation");
        set_rest_pose(t, node_index);
    }
    if (!animation.channels.empty()) model.animations.push_back(std::move(animation));
    add_scene();
    return write_glb_with_tail(file, model, keys_out.bytes(), [&] { return keys_out.write(file); }, &meshopt);
}

Result<void> ChainsGlbWriter::finish() {
    Impl& w = *impl_;
    if (w.added != w.frames) {
        return make_error(Error::Kind::InvalidInput, w.path + ": " + std::to_string(w.added) + " of " +
                                                         std::to_string(w.frames) + " frames added");
    }
    return write_file_atomically(w.path, [&](AtomicFile& file) {
        return w.compaction.enabled ? w.build_and_write_compact(file) : w.build_and_write(file);
    });
}

const GlbCompactionStats& ChainsGlbWriter::compaction_stats() const { return impl_->stats; }

bool ChainsGlbWriter::can_share() const {
    const Impl& w = *impl_;
    return w.compaction.enabled && !w.compaction.meshopt && !is_device_or_pipe(w.path);
}

Result<void> ChainsGlbWriter::share(std::size_t begin, std::size_t end) {
    Impl& w = *impl_;
    KW_TRY(check_share(w.path, can_share(), "compacted keys without meshopt, and a regular file", "characters", begin, end,
                       w.character_tracks.size() - 1, w.added > 0));
    w.shared = true;
    w.own_begin = begin;
    w.own_end = end;
    w.row.assign(w.own_tracks() * kRecordFloats, 0.0f);
    return {};
}

Result<void> ChainsGlbWriter::finish(Communicator& ranks) {
    Impl& w = *impl_;
    assert(w.shared && "finish(ranks) of a writer that share() made one rank's");
    KW_TRY(ranks.agree(w.added != w.frames ? Result<void>{make_error(Error::Kind::InvalidInput,
                                                                     w.path + ": " + std::to_string(w.added) + " of " +
                                                                         std::to_string(w.frames) + " frames added")}
                                           : Result<void>{}));
    std::vector<float>().swap(w.previous);
    std::vector<float>().swap(w.row);
    // Rank 0's JSON holds every track's rest pose (frame 0): the others' follow its own.
    w.first.resize(w.track_nodes.size() * kRecordFloats);  // a rank without characters has none
    const std::span<const std::byte> rest =
        std::as_bytes(std::span(w.first).subspan(w.track_base() * kRecordFloats, w.own_tracks() * kRecordFloats));
    std::size_t track = w.character_tracks[w.own_end];
    constexpr std::size_t kRestBytes = kRecordFloats * sizeof(float);
    return finish_shared_glb(
        ranks, w.path, w.compact_own(), rest,
        [&](std::size_t rank, std::span<const std::byte> theirs) -> Result<void> {
            if (theirs.size() % kRestBytes != 0 || track + theirs.size() / kRestBytes > w.track_nodes.size() ||
                (rank + 1 == static_cast<std::size_t>(ranks.size()) && track + theirs.size() / kRestBytes != w.track_nodes.size())) {
                return make_error(Error::Kind::Internal, w.path + ": rank " + std::to_string(rank) + "'s tracks do not fit");
            }
            std::memcpy(w.first.data() + track * kRecordFloats, theirs.data(), theirs.size());
            track += theirs.size() / kRestBytes;
            return {};
        },
        [&](AtomicFile& file, CompactKeys& keys) {
            w.joined = &keys;
            return w.build_and_write_compact(file);
        });
}

Result<void> write_chains_glb(const std::string& path, const RodScene& scene, std::uint32_t frames,
                              std::span<const glm::vec3> positions, std::span<const glm::quat> orientations,
                              const GlbCompaction& compaction) {
    const std::size_t joints = scene.world.joint_count;
    const std::size_t expected = std::size_t{frames} * joints;
    if (frames == 0) return make_error(Error::Kind::InvalidInput, path + ": cannot write an animation of 0 frames");
    if (positions.size() != expected || orientations.size() != expected) {
        return make_error(Error::Kind::InvalidInput, path + ": expected " + std::to_string(expected) +
                                                         " joint positions and orientations (frames x joints), got " +
                                                         std::to_string(positions.size()) + " and " +
                                                         std::to_string(orientations.size()));
    }
    auto writer = ChainsGlbWriter::create(path, scene, frames, compaction);
    if (!writer) return writer.error();
    for (std::uint32_t f = 0; f < frames; ++f) {
        KW_TRY(writer.value().add_frame(positions.subspan(std::size_t{f} * joints, joints),
                                        orientations.subspan(std::size_t{f} * joints, joints)));
    }
    return writer.value().finish();
}

}  // namespace kodawari
