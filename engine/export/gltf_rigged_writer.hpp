#pragma once
// What the files of the rigged crowd's glTF export share (not public): gltf_rigged.cpp
// (the keys, the model rebuilt and written) and gltf_rigged_source.cpp (the source file
// loaded and read): the writer's state.

#include <cmath>
#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>

#include "export/compact_keys.hpp"
#include "export/gltf_common.hpp"
#include "kodawari/export/export.hpp"

namespace kodawari {
namespace gltf {

inline bool finite(const glm::vec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }
inline bool finite(const glm::quat& q) {
    return std::isfinite(q.x) && std::isfinite(q.y) && std::isfinite(q.z) && std::isfinite(q.w);
}

// One key of one animated node.
struct Key {
    glm::vec3 translation;
    glm::quat rotation;
    glm::vec3 scale;
};

}  // namespace gltf

struct RiggedGlbWriter::Impl {
    std::string source_path;
    tinygltf::Model model;                          // the source, images' bytes moved out
    std::vector<std::vector<unsigned char>> image_bytes;  // per image: its bytes when given by URI
    std::vector<RiggedInstance> instances;
    float fps = 0.0f;
    std::string animation_name;

    // Per file node.
    std::size_t node_count = 0;
    std::vector<std::string> names;                 // "<name>" or "#<n>"
    std::vector<int> roots;                         // of the displayed scene
    std::vector<bool> animated;
    std::vector<bool> matrix;                       // given by a matrix in the file
    std::vector<glm::vec3> rest_translation;        // Character's TRS (matrices decomposed)
    std::vector<glm::quat> rest_rotation;
    std::vector<glm::vec3> rest_scale;
    std::vector<bool> skinned;                      // has a mesh and a skin
    std::vector<bool> moves;                        // skinned mesh node moved to the scene root
    std::vector<int> extra;                         // index of its extra skinned-mesh node, or -1
    std::size_t extra_count = 0;
    std::vector<int> animated_nodes;                // the animated nodes, ascending

    // Keys, frame-major in the spill file: frame f's key of track i * animated_nodes.size()
    // + k at (f * tracks + track) * sizeof(Key). Per track in memory: the last rotation
    // (hemispheres) and whether the scale ever left the rest scale.
    std::string spill_beside;
    std::optional<gltf::SpillFile> keys;
    std::vector<gltf::Key> row;
    std::vector<glm::quat> previous;
    std::vector<bool> scaled;  // per own track; on a shared writer's rank 0 at finish, every track's
    std::uint32_t frames = 0;
    bool finished = false;
    // The instances whose keys this writer keeps: all, or one rank's (share()), and a
    // shared writer's keys joined with the other ranks' (rank 0, at finish).
    std::size_t own_begin = 0;
    std::size_t own_end = 0;
    bool shared = false;
    gltf::CompactKeys* joined = nullptr;  // finish_shared_glb()'s, while rank 0 writes
    GlbCompaction compaction;
    GlbCompactionStats stats;

    [[nodiscard]] std::size_t stride() const { return 1 + node_count + extra_count; }
    [[nodiscard]] int out_node(std::size_t instance, int node) const {
        return static_cast<int>(instance * stride() + 1) + node;
    }
    [[nodiscard]] std::size_t tracks() const { return instances.size() * animated_nodes.size(); }
    [[nodiscard]] std::size_t own() const { return own_end - own_begin; }
    [[nodiscard]] std::size_t own_tracks() const { return own() * animated_nodes.size(); }
    [[nodiscard]] Result<gltf::CompactKeys> compact_own();

    Result<void> build_and_write(AtomicFile& file);
    [[nodiscard]] Result<void> copy_tracks(AtomicFile& file);
    [[nodiscard]] Result<void> write_compact(AtomicFile& file, tinygltf::Model& out, std::vector<unsigned char>& bytes);
};

}  // namespace kodawari
