// glTF 2.0 export of a crowd of one rigged character (export.hpp, RiggedGlbWriter): the
// source file's own meshes, materials, images and skins, node copies per instance, and
// one baked animation. The source is loaded with tinygltf and written back with it, so
// that every property and extension tinygltf knows travels unchanged; only buffers,
// images, nodes, skins, scenes and animations are rebuilt.

#include <algorithm>
#include <array>
#include <cassert>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <initializer_list>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "kodawari/core/version.hpp"
#include "export/compact_keys.hpp"
#include "export/shared_glb.hpp"
#include "export/gltf_common.hpp"
#include "export/gltf_rigged_writer.hpp"
#include "kodawari/export/export.hpp"

namespace kodawari {
namespace {

using namespace gltf;

// VRM's extensions name nodes of one character by index (humanoid bones, spring bones,
// constraints, look-at); they cannot describe the copies, so they are not carried.
bool is_vrm_extension(const std::string& name) { return name == "VRM" || name.rfind("VRMC_", 0) == 0; }

void strip_vrm(tinygltf::ExtensionMap& extensions) {
    std::erase_if(extensions, [](const auto& entry) { return is_vrm_extension(entry.first); });
}

void strip_vrm(std::vector<std::string>& names) { std::erase_if(names, is_vrm_extension); }

std::vector<double> to_doubles(const glm::vec3& v) {
    return {static_cast<double>(v.x), static_cast<double>(v.y), static_cast<double>(v.z)};
}

// glTF order: x, y, z, w.
std::vector<double> to_doubles(const glm::quat& q) {
    return {static_cast<double>(q.x), static_cast<double>(q.y), static_cast<double>(q.z), static_cast<double>(q.w)};
}

}  // namespace

RiggedGlbWriter::RiggedGlbWriter(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
RiggedGlbWriter::RiggedGlbWriter(RiggedGlbWriter&& other) noexcept = default;
RiggedGlbWriter& RiggedGlbWriter::operator=(RiggedGlbWriter&& other) noexcept = default;
RiggedGlbWriter::~RiggedGlbWriter() = default;

Result<void> RiggedGlbWriter::add_frame(std::span<const glm::vec3> translation, std::span<const glm::quat> rotation,
                                        std::span<const glm::vec3> scale) {
    Impl& w = *impl_;
    assert(!w.finished);
    const std::size_t expected = w.own() * w.node_count;
    assert(translation.size() == expected && rotation.size() == expected && scale.size() == expected &&
           "add_frame takes instances x nodes values");
    (void)expected;
    const std::size_t tracks = w.own_tracks();
    if (!w.keys) {
        auto keys = SpillFile::open(w.spill_beside);
        if (!keys) return keys.error();
        w.keys.emplace(std::move(keys).value());
        w.row.resize(tracks);
        w.previous.resize(tracks);
        w.scaled.assign(tracks, false);
    }
    for (std::size_t i = 0; i < w.own(); ++i) {
        for (std::size_t k = 0; k < w.animated_nodes.size(); ++k) {
            const auto node = static_cast<std::size_t>(w.animated_nodes[k]);
            const std::size_t at = i * w.node_count + node;
            glm::quat q = rotation[at];
            const float length = glm::length(q);
            if (!finite(translation[at]) || !finite(q) || !finite(scale[at]) || !(length > 0.0f)) {
                return make_error(Error::Kind::InvalidInput,
                                  "frame " + std::to_string(w.frames) + ", instance " + w.instances[w.own_begin + i].name + ", node " +
                                      w.names[node] + ": the transform is not finite (or a zero rotation)");
            }
            q /= length;
            const std::size_t track = i * w.animated_nodes.size() + k;
            // Consecutive keys in one hemisphere, so that players interpolate the short way.
            if (w.frames > 0 && glm::dot(w.previous[track], q) < 0.0f) q = -q;
            w.row[track] = {translation[at], q, scale[at]};
        }
    }
    KW_TRY(w.keys->append(w.row.data(), w.row.size() * sizeof(Key)));
    for (std::size_t track = 0; track < tracks; ++track) {
        w.previous[track] = w.row[track].rotation;
        const auto node = static_cast<std::size_t>(w.animated_nodes[track % w.animated_nodes.size()]);
        if (w.row[track].scale != w.rest_scale[node]) w.scaled[track] = true;
    }
    ++w.frames;
    return {};
}

std::uint32_t RiggedGlbWriter::frames() const { return impl_->frames; }

const GlbCompactionStats& RiggedGlbWriter::compaction_stats() const { return impl_->stats; }

int RiggedGlbWriter::output_node(std::size_t instance, int node) const {
    assert(instance < impl_->instances.size() && node >= -1 && node < static_cast<int>(impl_->node_count));
    return impl_->out_node(instance, node);
}

int RiggedGlbWriter::skinned_mesh_node(std::size_t instance, int node) const {
    const Impl& w = *impl_;
    assert(instance < w.instances.size() && node >= 0 && node < static_cast<int>(w.node_count));
    if (!w.skinned[static_cast<std::size_t>(node)]) return -1;
    const int e = w.extra[static_cast<std::size_t>(node)];
    if (e < 0) return w.out_node(instance, node);
    return static_cast<int>(instance * w.stride() + 1 + w.node_count) + e;
}

Result<void> RiggedGlbWriter::Impl::build_and_write(AtomicFile& file) {
    tinygltf::Model out = std::move(model);
    finished = true;
    out.asset.version = "2.0";
    out.asset.generator = "kodawari " + std::string(version());

    // VRM: keep the meta object (author, license) before the extensions go.
    for (const char* name : {"VRMC_vrm", "VRM"}) {
        const auto it = out.extensions.find(name);
        if (it == out.extensions.end() || !it->second.IsObject() || !it->second.Has("meta")) continue;
        tinygltf::Value::Object extras;
        if (out.asset.extras.IsObject()) extras = out.asset.extras.Get<tinygltf::Value::Object>();
        extras["vrmMeta"] = it->second.Get("meta");
        out.asset.extras = tinygltf::Value(std::move(extras));
        break;
    }
    strip_vrm(out.extensions);
    strip_vrm(out.extensionsUsed);
    strip_vrm(out.extensionsRequired);
    for (tinygltf::Material& m : out.materials) strip_vrm(m.extensions);
    for (tinygltf::Mesh& m : out.meshes) {
        strip_vrm(m.extensions);
        for (tinygltf::Primitive& p : m.primitives) strip_vrm(p.extensions);
    }
    for (tinygltf::Texture& t : out.textures) strip_vrm(t.extensions);
    for (tinygltf::Image& i : out.images) strip_vrm(i.extensions);

    // One buffer: the source's buffers back to back (4-byte aligned, which keeps every
    // accessor's alignment), then the images given by URI, then the keys.
    std::vector<unsigned char> bytes;
    std::vector<std::size_t> base(out.buffers.size(), 0);
    if (!out.buffers.empty()) bytes = std::move(out.buffers[0].data);
    bytes.resize((bytes.size() + 3) & ~std::size_t{3});
    BufferWriter writer(bytes);
    for (std::size_t b = 1; b < out.buffers.size(); ++b) {
        base[b] = writer.append(out.buffers[b].data.data(), out.buffers[b].data.size());
        out.buffers[b].data = {};
    }
    for (tinygltf::BufferView& view : out.bufferViews) {
        view.byteOffset += base[static_cast<std::size_t>(view.buffer)];
        view.buffer = 0;
    }
    out.buffers.assign(1, tinygltf::Buffer{});
    for (std::size_t i = 0; i < out.images.size(); ++i) {
        std::vector<unsigned char>& data = image_bytes[i];
        if (data.empty()) continue;
        tinygltf::Image& image = out.images[i];
        image.bufferView = add_buffer_view(out, writer.append(data.data(), data.size()), data.size(), 0);
        image.uri.clear();
        data = {};
    }

    // Nodes and skins, instance by instance.
    std::vector<tinygltf::Node> source_nodes = std::move(out.nodes);
    std::vector<tinygltf::Skin> source_skins = std::move(out.skins);
    const int source_scene = out.defaultScene >= 0 ? out.defaultScene : 0;
    tinygltf::Scene scene;
    if (static_cast<std::size_t>(source_scene) < out.scenes.size()) scene = out.scenes[static_cast<std::size_t>(source_scene)];
    scene.nodes.clear();
    out.nodes.clear();
    out.nodes.reserve(instances.size() * stride());
    out.skins.clear();
    for (std::size_t i = 0; i < instances.size(); ++i) {
        const RiggedInstance& instance = instances[i];
        const std::string prefix = instance.name + "/";
        const int first_skin = static_cast<int>(i * source_skins.size());
        tinygltf::Node root;
        root.name = instance.name;
        root.translation = to_doubles(instance.placement.position);
        root.rotation = to_doubles(glm::normalize(instance.placement.rotation));
        for (const int r : roots) {
            if (!moves[static_cast<std::size_t>(r)]) root.children.push_back(out_node(i, r));
        }
        scene.nodes.push_back(static_cast<int>(out.nodes.size()));
        out.nodes.push_back(std::move(root));
        std::vector<tinygltf::Node> extras(extra_count);
        for (std::size_t k = 0; k < node_count; ++k) {
            tinygltf::Node node = source_nodes[k];
            node.name = prefix + names[k];
            strip_vrm(node.extensions);
            node.children.clear();
            for (const int c : source_nodes[k].children) {
                if (!moves[static_cast<std::size_t>(c)]) node.children.push_back(out_node(i, c));
            }
            if (node.skin >= 0) node.skin += first_skin;
            if (animated[k] && matrix[k]) {
                node.matrix.clear();
                node.translation = to_doubles(rest_translation[k]);
                node.rotation = to_doubles(rest_rotation[k]);
                node.scale = to_doubles(rest_scale[k]);
            }
            if (moves[k]) {
                // Skinning ignores the node's transform (§3.7.3); glTF-Validator warns about
                // one that is there (NODE_SKINNED_MESH_LOCAL_TRANSFORMS).
                node.translation.clear();
                node.rotation.clear();
                node.scale.clear();
                node.matrix.clear();
                scene.nodes.push_back(out_node(i, static_cast<int>(k)));
            } else if (extra[k] >= 0) {
                tinygltf::Node& mesh_node = extras[static_cast<std::size_t>(extra[k])];
                mesh_node.name = node.name + "/skinned mesh";
                mesh_node.mesh = std::exchange(node.mesh, -1);
                mesh_node.skin = std::exchange(node.skin, -1);
                mesh_node.weights = std::exchange(node.weights, {});
                scene.nodes.push_back(static_cast<int>(i * stride() + 1 + node_count) + extra[k]);
            }
            out.nodes.push_back(std::move(node));
        }
        for (tinygltf::Node& node : extras) out.nodes.push_back(std::move(node));
        for (const tinygltf::Skin& source : source_skins) {
            tinygltf::Skin skin = source;
            skin.name = prefix + (source.name.empty() ? "skin" : source.name);
            strip_vrm(skin.extensions);
            for (int& j : skin.joints) j = out_node(i, j);
            if (skin.skeleton >= 0) skin.skeleton = out_node(i, skin.skeleton);
            out.skins.push_back(std::move(skin));
        }
    }
    out.scenes.assign(1, std::move(scene));
    out.defaultScene = 0;

    // The animation: shared key times, then per track a buffer view holding its
    // translations, rotations and (when they change) scales.
    out.animations.clear();
    if (!animated_nodes.empty() && compaction.enabled) return write_compact(file, out, bytes);
    if (!animated_nodes.empty()) {
        std::vector<float> times(frames);
        for (std::uint32_t f = 0; f < frames; ++f) times[f] = static_cast<float>(f) / fps;
        const std::size_t time_bytes = times.size() * sizeof(float);
        const int time_view = add_buffer_view(out, writer.append(times.data(), time_bytes), time_bytes, 0);
        const int time_accessor = add_accessor(out, time_view, 0, TINYGLTF_COMPONENT_TYPE_FLOAT, frames, TINYGLTF_TYPE_SCALAR);
        out.accessors[static_cast<std::size_t>(time_accessor)].minValues = {static_cast<double>(times.front())};
        out.accessors[static_cast<std::size_t>(time_accessor)].maxValues = {static_cast<double>(times.back())};

        tinygltf::Animation animation;
        animation.name = animation_name;
        auto add_channel = [&](int node, int accessor, const char* path) {
            add_linear_channel(animation, time_accessor, accessor, node, path);
        };
        // The tracks' views follow the buffer's head (the source's data, the images, the
        // times) back to back; their bytes come from the spill file as the file is written.
        std::size_t offset = bytes.size();
        for (std::size_t i = 0; i < instances.size(); ++i) {
            for (std::size_t k = 0; k < animated_nodes.size(); ++k) {
                const bool scale_keys = scaled[i * animated_nodes.size() + k];
                const std::size_t size = std::size_t{frames} * (scale_keys ? 10 : 7) * sizeof(float);
                const int view = add_buffer_view(out, offset, size, 0);
                offset += size;
                const int node = out_node(i, animated_nodes[k]);
                add_channel(node, add_accessor(out, view, 0, TINYGLTF_COMPONENT_TYPE_FLOAT, frames, TINYGLTF_TYPE_VEC3),
                            "translation");
                add_channel(node,
                            add_accessor(out, view, std::size_t{frames} * 3 * sizeof(float), TINYGLTF_COMPONENT_TYPE_FLOAT,
                                         frames, TINYGLTF_TYPE_VEC4),
                            "rotation");
                if (scale_keys) {
                    add_channel(node,
                                add_accessor(out, view, std::size_t{frames} * 7 * sizeof(float),
                                             TINYGLTF_COMPONENT_TYPE_FLOAT, frames, TINYGLTF_TYPE_VEC3),
                                "scale");
                }
            }
        }
        out.animations.push_back(std::move(animation));
        const std::uint64_t tail = offset - bytes.size();
        out.buffers[0].data = std::move(bytes);
        return write_glb_with_tail(file, out, tail, [&] { return copy_tracks(file); });
    }
    if (bytes.empty()) {
        out.buffers.clear();  // glTF-Validator rejects an empty buffer
    } else {
        out.buffers[0].data = std::move(bytes);
    }
    return write_glb(file, out);
}

// GlbCompaction: the keys are reduced first (compact_keys.hpp) into a second temporary
// file whose bytes follow the buffer's head (the source's data and images) as its tail,
// one buffer view; each channel's key times and values are accessors into it. A scale
// channel only for the nodes whose scale leaves the rest scale, as uncompacted.
// The own tracks' keys compacted: every track's, or one rank's.
Result<CompactKeys> RiggedGlbWriter::Impl::compact_own() {
    std::vector<float> times(frames);
    for (std::uint32_t f = 0; f < frames; ++f) times[f] = static_cast<float>(f) / fps;
    constexpr std::array<ChannelKind, 3> kFields = {ChannelKind::Translation, ChannelKind::Rotation, ChannelKind::Scale};
    if (!keys) {  // no frame added (finish() refuses that) or, shared, no instance of its own
        auto opened = SpillFile::open(spill_beside);
        if (!opened) return opened.error();
        keys.emplace(std::move(opened).value());
    }
    return CompactKeys::build(*keys, spill_beside, own_tracks(), kFields, times, compaction, RiggedGlbWriter::kTransposeBytes,
                              [&](std::size_t track, std::size_t field) { return field != 2 || scaled[track]; });
}

Result<void> RiggedGlbWriter::Impl::write_compact(AtomicFile& file, tinygltf::Model& out, std::vector<unsigned char>& bytes) {
    static_assert(sizeof(Key) == 10 * sizeof(float));
    std::optional<Result<CompactKeys>> built_here;
    if (joined == nullptr) {
        built_here.emplace(compact_own());
        if (!*built_here) return built_here->error();
    }
    CompactKeys& keys_out = joined != nullptr ? *joined : built_here->value();
    stats = keys_out.stats();
    MeshoptJson meshopt;
    const int view = keys_out.add_views(out, bytes.size(), meshopt);
    tinygltf::Animation animation;
    animation.name = animation_name;
    for (std::size_t i = 0; i < instances.size(); ++i) {
        for (std::size_t k = 0; k < animated_nodes.size(); ++k) {
            const int node = out_node(i, animated_nodes[k]);
            const auto translation = keys_out.add_next_channel(out, view);
            add_linear_channel(animation, translation.first, translation.second, node, "translation");
            const auto rotation = keys_out.add_next_channel(out, view);
            add_linear_channel(animation, rotation.first, rotation.second, node, "rotation");
            if (scaled[i * animated_nodes.size() + k]) {
                const auto scale = keys_out.add_next_channel(out, view);
                add_linear_channel(animation, scale.first, scale.second, node, "scale");
            }
        }
    }
    out.animations.push_back(std::move(animation));
    out.buffers[0].data = std::move(bytes);
    return write_glb_with_tail(file, out, keys_out.bytes(), [&] { return keys_out.write(file); }, &meshopt);
}

// The spill file holds frames x tracks keys; the .glb per track its translations over
// all frames, then its rotations, then its scales when they change. A group of tracks at
// a time: read its keys of every frame (one contiguous run per frame), write its views.
Result<void> RiggedGlbWriter::Impl::copy_tracks(AtomicFile& file) {
    // A Key is translation, rotation (x, y, z, w), scale: ten floats; the scale only of
    // the nodes whose clips scale them.
    static_assert(sizeof(Key) == 10 * sizeof(float));
    constexpr std::array<std::size_t, 3> kFields = {3, 4, 3};
    return copy_item_major(*keys, file, tracks(), frames, kFields, RiggedGlbWriter::kTransposeBytes,
                           [&](std::size_t track, std::size_t field) { return field != 2 || scaled[track]; });
}

bool RiggedGlbWriter::can_share() const {
    const Impl& w = *impl_;
    return w.compaction.enabled && !w.compaction.meshopt && !w.animated_nodes.empty() && !w.spill_beside.empty() &&
           !is_device_or_pipe(w.spill_beside);
}

Result<void> RiggedGlbWriter::share(std::size_t begin, std::size_t end) {
    Impl& w = *impl_;
    KW_TRY(check_share(w.spill_beside, can_share(), "compacted keys without meshopt, animated nodes, and a regular file",
                       "instances", begin, end, w.instances.size(), w.frames > 0));
    w.shared = true;
    w.own_begin = begin;
    w.own_end = end;
    return {};
}

Result<void> RiggedGlbWriter::finish(Communicator& ranks, const std::string& path) {
    Impl& w = *impl_;
    assert(w.shared && !w.finished && "finish(ranks, path) once, of a writer that share() made one rank's");
    KW_TRY(ranks.agree(w.frames == 0 ? Result<void>{make_error(Error::Kind::InvalidInput, path + ": no frames to write")}
                                     : Result<void>{}));
    // Rank 0 writes every track's channels, the scale only where it changes: the other
    // ranks' tracks say which of theirs do (a byte each), in rank order after its own.
    w.scaled.resize(w.own_tracks());  // an instance-less rank never sized them
    std::vector<std::byte> mine(w.scaled.size());
    for (std::size_t t = 0; t < mine.size(); ++t) mine[t] = std::byte{static_cast<unsigned char>(w.scaled[t])};
    std::vector<bool> every = w.scaled;
    return finish_shared_glb(
        ranks, path, w.compact_own(), mine,
        [&](std::size_t rank, std::span<const std::byte> theirs) -> Result<void> {
            if (every.size() + theirs.size() > w.tracks() ||
                (rank + 1 == static_cast<std::size_t>(ranks.size()) && every.size() + theirs.size() != w.tracks())) {
                return make_error(Error::Kind::Internal, path + ": rank " + std::to_string(rank) + "'s tracks do not fit");
            }
            for (const std::byte b : theirs) every.push_back(b != std::byte{0});
            return {};
        },
        [&](AtomicFile& file, CompactKeys& keys) {
            w.scaled = std::move(every);
            w.joined = &keys;
            return w.build_and_write(file);
        });
}

Result<void> RiggedGlbWriter::finish(const std::string& path) {
    Impl& w = *impl_;
    assert(!w.finished && "finish() once");
    if (w.frames == 0) return make_error(Error::Kind::InvalidInput, path + ": no frames to write");
    return write_file_atomically(path, [&](AtomicFile& file) { return w.build_and_write(file); });
}

}  // namespace kodawari
