#pragma once
// What the files of the bird glTF export share (not public): gltf_birds.cpp (the writer:
// keys, the model, the finish), gltf_birds_meshes.cpp (the wing types' meshes and skins'
// inverse bind matrices) and gltf_birds_elements.cpp (each bird's nodes, skin and
// animation channels): the writer's state and where each bird's elements go.

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "export/compact_keys.hpp"
#include "export/gltf_common.hpp"
#include "kodawari/birds/rig.hpp"
#include "kodawari/export/export.hpp"

namespace kodawari {

/// What the birds of one wing type share in the file.
struct WingTypeAssets {
    int mesh = -1;
    int inverse_bind = -1;  // accessor of the skin's 7 inverse bind matrices
    std::array<std::array<float, 3>, birds::kPartCount> offsets{};
};

/// Adds the material, the skinned mesh and the inverse bind matrices of one wing type
/// (gltf_birds_meshes.cpp).
WingTypeAssets add_wing_type(tinygltf::Model& model, gltf::BufferWriter& writer, birds::WingType type);

// One bird's keys of one frame: the Body translation, the parts' rotations, the Tail's
// scale (1 + s, 1, 1) from its spread s (BirdPose.position.w). The scale is kept in the
// key file always but written only when some bird spreads its tail in the run: a flock
// that never does (every wing type but those the glide and landing modes fan) would
// otherwise carry a constant channel per bird.
constexpr std::size_t kRecordFloats = 3 + 4 * birds::kPartCount + 3;
constexpr std::size_t kTailScaleAt = 3 + 4 * birds::kPartCount;
constexpr std::size_t kTailScaleField = 1 + birds::kPartCount;  // the record's fields: translation, rotations, scale
// The bytes a bird's frame takes in the .glb without the tail's scale (the 4 GiB check
// before the run; with it, write_streamed_glb() checks again before writing).
constexpr std::size_t kRecordBytes = (kRecordFloats - 3) * sizeof(float);

struct BirdGlbWriter::Impl {
    std::string path;
    const birds::BirdWorld* world = nullptr;
    // The birds of the built-in wing types, in world order: a user's model's birds go to
    // their own file (BirdModelExport, gltf_bird_models.cpp). Bird b of this file is
    // world->birds[exported[b]].
    std::vector<std::uint32_t> exported;
    std::uint32_t frames = 0;
    std::uint32_t added = 0;
    // The birds whose keys this writer keeps: all of them, or one rank's of a distributed
    // bake (share(); then every bird is exported, and add_frames() gets these alone).
    std::size_t own_begin = 0;
    std::size_t own_end = 0;
    bool shared = false;
    gltf::SpillFile keys;  // frames x own birds records
    std::vector<float> first;     // birds x record: frame 0, the rest pose (all birds)
    std::vector<float> previous;  // own birds x record: the last frame added (rotation hemispheres)
    std::vector<float> row;       // own birds x record being written
    // A shared writer's compacted keys, every rank's joined (rank 0, while it writes:
    // finish_shared_glb() owns them, and reads where they were written).
    gltf::CompactKeys* joined = nullptr;
    GlbCompaction compaction;
    GlbCompactionStats stats;
    bool tail_spread = false;  // some bird's tail spread s is not 0 in some frame

    [[nodiscard]] std::size_t count() const { return exported.size(); }
    [[nodiscard]] std::size_t own() const { return own_end - own_begin; }
    [[nodiscard]] std::uint32_t type_of(std::size_t b) const { return world->birds[exported[b]].ids.y; }
    [[nodiscard]] std::string name_of(std::size_t b) const {
        return std::string(birds::wing_type_spec(static_cast<birds::WingType>(type_of(b))).name) + "_" +
               std::to_string(exported[b]);
    }
    [[nodiscard]] Result<void> add_frame(std::span<const gpu::BirdPose> poses);
    [[nodiscard]] Result<gltf::CompactKeys> compact_own();
    [[nodiscard]] Result<void> build_and_write(AtomicFile& file);
    [[nodiscard]] Result<void> copy_channels(AtomicFile& file);

    // The JSON's per-bird elements, made while it is written (build_and_write()).
    struct Layout;
    void root_node(std::vector<tinygltf::Node>& out) const;
    void bird_nodes(const Layout& layout, std::size_t b, std::vector<tinygltf::Node>& out) const;
    void bird_skin(const Layout& layout, std::size_t b, std::vector<tinygltf::Skin>& out) const;
    void bird_accessors(const Layout& layout, std::size_t b, std::vector<tinygltf::Accessor>& out) const;
    void bird_samplers(const Layout& layout, std::size_t b, std::vector<tinygltf::AnimationSampler>& out) const;
    void bird_channels(const Layout& layout, std::size_t b, std::vector<tinygltf::AnimationChannel>& out) const;
};

// Where bird b's elements go, as build_and_write() laid out the model: node 0 the root
// of every armature, then per bird kNodesPerBird nodes (its armature's root, the 7 joints
// in part order, its mesh node), skin b, accessors first_accessor + channels x b + k and
// the samplers and channels channels x b + k of animation 0 (k = 0: the Body's
// translation, 1 + part: the part's rotation, 1 + kPartCount: the Tail's scale when
// written), the keys in the animation view at time_bytes + b x per_bird.
struct BirdGlbWriter::Impl::Layout {
    std::array<WingTypeAssets, birds::kWingTypeCount> types{};
    int animation_view = -1;
    int time_accessor = -1;
    int first_accessor = -1;
    std::size_t channels = 1 + birds::kPartCount;
    std::size_t time_bytes = 0;
    std::size_t translation_bytes = 0;
    std::size_t rotation_bytes = 0;
    std::size_t per_bird = 0;
    // Compacted: the channels' accessors and their key times come from `compact` (the
    // buffer view `animation_view` holds its tail), bird b's from first_accessor +
    // compact->accessors_before(b) on.
    const gltf::CompactKeys* compact = nullptr;

    static constexpr std::size_t kNodesPerBird = 2 + birds::kPartCount;
    [[nodiscard]] static int armature_node(std::size_t b) { return static_cast<int>(1 + b * kNodesPerBird); }
    [[nodiscard]] static int joint_node(std::size_t b, std::size_t part) {
        return armature_node(b) + 1 + static_cast<int>(part);
    }
    [[nodiscard]] static int mesh_node(std::size_t b) { return armature_node(b) + 1 + static_cast<int>(birds::kPartCount); }
};

}  // namespace kodawari
