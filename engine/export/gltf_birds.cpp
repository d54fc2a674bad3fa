// glTF 2.0 export of a bird simulation (SPEC C): per bird one armature (a root node named
// after the bird, the 7 parts as joints), one skin and one mesh node; one skinned mesh
// per wing type (the parts' closed meshes merged, each vertex rigidly on its part's
// joint) shared with its inverse bind matrices by every bird of the type; and one
// animation whose channels hold every simulated frame. As the rigged crowd's export
// (gltf_rigged.cpp), the channels of one bird drive only its own armature, so Blender's
// importer makes one armature and one action per bird (issue 14; before, 7 animated
// objects and 7 actions per bird). Streamed (BirdGlbWriter): keys arrive frame by frame
// but glTF keeps each channel's keys together, so they wait in a temporary file.

#include <algorithm>
#include <array>
#include <cassert>
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

#include "kodawari/core/version.hpp"
#include "export/compact_keys.hpp"
#include "export/gltf_birds_writer.hpp"
#include "export/gltf_common.hpp"
#include "export/gltf_json_stream.hpp"
#include "export/shared_glb.hpp"
#include "kodawari/birds/rig.hpp"
#include "kodawari/export/export.hpp"

namespace kodawari {
namespace {

using namespace gltf;

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

}  // namespace

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
    // Each bird also costs its armature, skin and animation's JSON whatever the frames:
    // 3 209 bytes measured (1 000 and 2 000 pigeons, 1 and 2 frames), counted as 3 000 so
    // that no file that fits is refused; a million birds are 3 GB of it.
    constexpr double kBirdBytes = 3000.0;
    const double poses = static_cast<double>(frames) * static_cast<double>(bird_count);
    const double bytes = poses * static_cast<double>(kRecordBytes) + static_cast<double>(bird_count) * kBirdBytes;
    if (!compaction.enabled && bytes > 4.0e9) {
        return make_error(Error::Kind::InvalidInput,
                          path + ": " + std::to_string(std::uint64_t{frames} * bird_count) + " poses of " +
                              std::to_string(bird_count) + " birds exceed the 4 GiB limit of a .glb (about " +
                              std::to_string(static_cast<std::uint64_t>(bytes / 1e6)) +
                              " MB; bake fewer birds or frames, or compact the keys: --compact)");
    }
    auto impl = std::make_unique<Impl>();
    for (std::size_t b = 0; b < bird_count; ++b) {
        const std::uint32_t type = world.birds[b].ids.y;
        if (type >= birds::kWingTypeCount + world.models.size()) {
            return make_error(Error::Kind::InvalidInput,
                              path + ": bird " + std::to_string(b) + " has unknown wing type " + std::to_string(type));
        }
        if (type < birds::kWingTypeCount) impl->exported.push_back(static_cast<std::uint32_t>(b));
    }
    impl->path = path;
    impl->world = &world;
    impl->frames = frames;
    impl->compaction = compaction;
    auto keys = SpillFile::open(path);
    if (!keys) return keys.error();
    impl->keys = std::move(keys).value();
    impl->own_end = impl->exported.size();
    impl->row.resize(impl->exported.size() * kRecordFloats);
    return BirdGlbWriter(std::move(impl));
}

Result<void> BirdGlbWriter::add_frames(std::span<const gpu::BirdPose> poses) {
    Impl& w = *impl_;
    const std::size_t count = w.shared ? w.own() : w.world->birds.size();
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
    // A shared writer's poses are its own birds' (every bird exported: b is their index).
    const std::size_t pose_base = shared ? own_begin : 0;
    for (std::size_t i = 0; i < own(); ++i) {
        const std::size_t b = exported[own_begin + i];
        const gpu::BirdPose& pose = poses[b - pose_base];
        float* record = row.data() + i * kRecordFloats;
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
                const float* p = previous.data() + i * kRecordFloats + 3 + 4 * part;
                const float dot = p[0] * q[0] + p[1] * q[1] + p[2] * q[2] + p[3] * q[3];
                if (dot < 0.0f) {
                    for (float& v : q) v = -v;
                }
            }
            std::memcpy(record + 3 + 4 * part, q.data(), sizeof(Quat));
        }
        const float spread = pose.position.w;
        if (!std::isfinite(spread)) {
            return make_error(Error::Kind::Internal,
                              "bird " + std::to_string(b) + ", frame " + std::to_string(f) + ": tail spread is not finite");
        }
        if (spread != 0.0f) tail_spread = true;
        record[kTailScaleAt] = 1.0f + spread;
        record[kTailScaleAt + 1] = 1.0f;
        record[kTailScaleAt + 2] = 1.0f;
    }
    KW_TRY(keys.append(row.data(), row.size() * sizeof(float)));
    if (f == 0) {
        first.resize(count() * kRecordFloats);
        std::copy(row.begin(), row.end(), first.begin() + static_cast<std::ptrdiff_t>(own_begin * kRecordFloats));
    }
    previous.swap(row);
    row.resize(previous.size());
    ++added;
    return {};
}

// The key file holds frames x birds records; the .glb per bird its translations over all
// frames, then each part's rotations. A group of birds at a time: read its records of
// every frame (one contiguous run per frame), write its channels.
Result<void> BirdGlbWriter::Impl::copy_channels(AtomicFile& file) {
    std::array<std::size_t, 2 + birds::kPartCount> fields{};
    fields.fill(4);
    fields[0] = 3;
    fields[kTailScaleField] = 3;
    return copy_item_major(keys, file, count(), frames, fields, BirdGlbWriter::kTransposeBytes,
                           [&](std::size_t, std::size_t field) { return field != kTailScaleField || tail_spread; });
}

// The own birds' keys compacted (CompactKeys): every bird's, or one rank's.
Result<CompactKeys> BirdGlbWriter::Impl::compact_own() {
    std::vector<float> times(frames);
    for (std::uint32_t f = 0; f < frames; ++f) times[f] = static_cast<float>(f) / world->fps;
    std::array<ChannelKind, 2 + birds::kPartCount> fields{};
    fields.fill(ChannelKind::Rotation);
    fields[0] = ChannelKind::Translation;
    fields[kTailScaleField] = ChannelKind::Scale;
    return CompactKeys::build(keys, path, own(), fields, times, compaction, BirdGlbWriter::kTransposeBytes,
                              [&](std::size_t, std::size_t field) { return field != kTailScaleField || tail_spread; });
}

// The model holds what does not grow with the flock (meshes, materials, the key times);
// the birds' nodes, accessors, channels and samplers are made one bird at a time while
// the JSON is written (write_streamed_glb), and their keys copied from the key file.
Result<void> BirdGlbWriter::Impl::build_and_write(AtomicFile& file) {
    const std::size_t bird_count = count();
    tinygltf::Model model;
    model.asset.version = "2.0";
    model.asset.generator = "kodawari " + std::string(version());
    // Room for meshopt's fallback buffer (CompactKeys::add_views), which must not move
    // buffer 0's bytes while `bytes` and `writer` refer to them.
    model.buffers.reserve(2);
    model.buffers.emplace_back();
    std::vector<unsigned char>& bytes = model.buffers[0].data;
    BufferWriter writer(bytes);
    Layout layout;

    // Meshes first, only for the wing types that occur.
    std::array<bool, birds::kWingTypeCount> used{};
    for (std::size_t b = 0; b < bird_count; ++b) used[type_of(b)] = true;
    for (std::size_t t = 0; t < birds::kWingTypeCount; ++t) {
        if (used[t]) layout.types[t] = add_wing_type(model, writer, static_cast<birds::WingType>(t));
    }
    layout.channels = 1 + birds::kPartCount + (tail_spread ? 1 : 0);

    // Animation data: the shared key times (in memory), then per bird its Body
    // translation and the rotations of its parts, each channel contiguous over the frames
    // (the tail, copied from the key file). Compacted (GlbCompaction), the tail is
    // CompactKeys' instead, key times included, in one buffer view after the meshes.
    layout.time_bytes = frames * sizeof(float);
    layout.translation_bytes = frames * 3 * sizeof(float);
    layout.rotation_bytes = frames * 4 * sizeof(float);
    layout.per_bird = layout.translation_bytes + birds::kPartCount * layout.rotation_bytes +
                      (tail_spread ? layout.translation_bytes : 0);
    const float fps = world->fps;
    std::optional<CompactKeys> built_here;
    CompactKeys* compact = nullptr;  // joined's (a shared writer's rank 0) or built here
    StreamedElements streamed;
    if (compaction.enabled) {
        if (joined != nullptr) {
            compact = joined;
        } else {
            auto built = compact_own();
            if (!built) return built.error();
            compact = &built_here.emplace(std::move(built).value());
        }
        stats = compact->stats();
        layout.compact = compact;
        layout.animation_view = compact->add_views(model, bytes.size(), streamed.meshopt);
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

    // Node 0 is the root, then each bird's armature root, joints and mesh node.
    streamed.nodes.groups = 1 + bird_count;
    streamed.nodes.fill = [&](std::size_t group, std::vector<tinygltf::Node>& out) {
        if (group == 0) {
            root_node(out);
        } else {
            bird_nodes(layout, group - 1, out);
        }
    };
    streamed.skins.groups = bird_count;
    streamed.skins.fill = [&](std::size_t b, std::vector<tinygltf::Skin>& out) { bird_skin(layout, b, out); };
    streamed.accessors.groups = bird_count;
    streamed.accessors.fill = [&](std::size_t b, std::vector<tinygltf::Accessor>& out) { bird_accessors(layout, b, out); };
    // An animation without channels is invalid glTF: a world without birds gets none.
    if (bird_count > 0) {
        tinygltf::Animation& animation = model.animations.emplace_back();
        animation.name = "flight";
        streamed.channels.groups = bird_count;
        streamed.channels.fill = [&](std::size_t b, std::vector<tinygltf::AnimationChannel>& out) {
            bird_channels(layout, b, out);
        };
        streamed.samplers.groups = bird_count;
        streamed.samplers.fill = [&](std::size_t b, std::vector<tinygltf::AnimationSampler>& out) {
            bird_samplers(layout, b, out);
        };
    }

    tinygltf::Scene scene;
    scene.name = "flock";
    scene.nodes.reserve(1 + bird_count);
    scene.nodes.push_back(0);
    for (std::size_t b = 0; b < bird_count; ++b) scene.nodes.push_back(Layout::mesh_node(b));
    model.scenes.push_back(std::move(scene));
    model.defaultScene = 0;

    if (compact) return write_streamed_glb(file, model, streamed, compact->bytes(), [&] { return compact->write(file); });
    return write_streamed_glb(file, model, streamed, std::uint64_t{bird_count} * layout.per_bird,
                              [&] { return copy_channels(file); });
}

Result<void> BirdGlbWriter::finish() {
    Impl& w = *impl_;
    if (!w.world->birds.empty() && w.added != w.frames) {
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

bool BirdGlbWriter::can_share() const {
    const Impl& w = *impl_;
    return w.compaction.enabled && !w.compaction.meshopt && w.count() == w.world->birds.size() && !is_device_or_pipe(w.path);
}

Result<void> BirdGlbWriter::share(std::size_t begin, std::size_t end) {
    Impl& w = *impl_;
    KW_TRY(check_share(w.path, can_share(), "compacted keys without meshopt, built-in wing types only, and a regular file",
                       "birds", begin, end, w.count(), w.added > 0));
    w.shared = true;
    w.own_begin = begin;
    w.own_end = end;
    w.row.assign(w.own() * kRecordFloats, 0.0f);
    return {};
}

// The collective finish of a shared writer (export.hpp). Every step that can fail on one
// rank ends in an agreement, so that no rank waits in a gather or broadcast that another
// has left; rank 0 always broadcasts the plan once, empty when it failed before it.
Result<void> BirdGlbWriter::finish(Communicator& ranks) {
    Impl& w = *impl_;
    assert(w.shared && "finish(ranks) of a writer that share() made one rank's");
    const bool root = ranks.rank() == 0;
    Result<void> ready;
    if (w.own() > 0 && w.added != w.frames) {
        ready = make_error(Error::Kind::InvalidInput, w.path + ": " + std::to_string(w.added) + " of " +
                                                          std::to_string(w.frames) + " frames added");
    }
    KW_TRY(ranks.agree(ready));
    std::vector<float>().swap(w.previous);
    std::vector<float>().swap(w.row);

    // Whether the tail's scale is written is every bird's business: any rank's.
    std::vector<std::byte> all;
    std::vector<std::size_t> sizes;
    const std::byte spread_here{static_cast<unsigned char>(w.tail_spread ? 1 : 0)};
    ranks.gather(std::span(&spread_here, 1), all, sizes);
    std::vector<std::byte> spread{spread_here};
    if (root) spread[0] = std::byte{static_cast<unsigned char>(std::any_of(all.begin(), all.end(), [](std::byte b) {
                                        return b != std::byte{0};
                                    }))};
    ranks.broadcast(spread);
    w.tail_spread = spread.size() == 1 && spread[0] != std::byte{0};

    // Each rank compacts its own birds' channels; rank 0 also needs the others' rest
    // poses (frame 0), which its JSON holds, and writes the file (shared_glb.hpp).
    w.first.resize(w.count() * kRecordFloats);  // rank 0 may have no bird of its own
    const std::span<const std::byte> rest =
        std::as_bytes(std::span(w.first).subspan(w.own_begin * kRecordFloats, w.own() * kRecordFloats));
    std::size_t bird = w.own_end;  // rank 0's next bird: the ranks' birds follow in rank order
    constexpr std::size_t kRestBytes = kRecordFloats * sizeof(float);
    return finish_shared_glb(
        ranks, w.path, w.compact_own(), rest,
        [&](std::size_t rank, std::span<const std::byte> theirs) -> Result<void> {
            if (theirs.size() % kRestBytes != 0 || bird + theirs.size() / kRestBytes > w.count()) {
                return make_error(Error::Kind::Internal, w.path + ": rank " + std::to_string(rank) + "'s birds do not fit");
            }
            std::memcpy(w.first.data() + bird * kRecordFloats, theirs.data(), theirs.size());
            bird += theirs.size() / kRestBytes;
            if (rank + 1 == static_cast<std::size_t>(ranks.size()) && bird != w.count()) {
                return make_error(Error::Kind::Internal, w.path + ": the ranks' birds are not every bird");
            }
            return {};
        },
        [&](AtomicFile& file, CompactKeys& keys) {
            w.joined = &keys;
            return w.build_and_write(file);
        });
}

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
