#pragma once
/// @file
/// Rigged characters and their clips on the CPU (SPEC A.7, issue 4): the node hierarchy,
/// skins, clips and a per-node mesh reference, and the evaluation of a clip into a pose
/// (local TRS and world matrices of every node): namespace kodawari::animation, in the sim
/// library. The data model is glTF 2.0's, so the section numbers below refer to its
/// specification, version 2.0.1 (https://registry.khronos.org/glTF/specs/2.0/glTF-2.0.html);
/// loading one from `.gltf`, `.glb` or `.vrm` is gltf/import.hpp (kodawari::io).

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>

#include "kodawari/core/api.hpp"
#include "kodawari/core/result.hpp"
#include "kodawari/rods/solver.hpp"

namespace kodawari::animation {

/// One node of the hierarchy (§3.5.2 Nodes and Hierarchy, §3.5.3 Transformations).
struct Node {
    std::string name;
    int parent = -1;              ///< index of the parent node, -1 for a root
    std::vector<int> children;    ///< in the file's order
    /// The rest local transform. A node given by `matrix` has it decomposed here too
    /// (exact only for matrices without shear); `matrix` then holds the original, which
    /// world matrices use (§3.5.3: animated nodes have no matrix, checked at load).
    glm::vec3 translation{0.0f};
    glm::quat rotation{1.0f, 0.0f, 0.0f, 0.0f};
    glm::vec3 scale{1.0f};
    std::optional<glm::mat4> matrix;
    int mesh = -1;                ///< index into Character::meshes, -1 for none
    int skin = -1;                ///< index into Character::skins, -1 for none
};

/// What a mesh is, enough to display it later (§3.7.2 Meshes).
struct Mesh {
    std::string name;
    std::size_t primitives = 0;
    /// The triangle primitives (mode TRIANGLES) with their vertices, for display;
    /// primitives of other modes are left out.
    struct Triangles {
        std::vector<glm::vec3> positions;
        std::vector<glm::vec3> normals;   ///< unit; empty when the file has none
        std::vector<glm::uvec4> joints;   ///< JOINTS_0 (indices into the node's skin's joints); empty when unskinned
        std::vector<glm::vec4> weights;   ///< WEIGHTS_0, one per joints entry
        std::vector<std::uint32_t> indices;  ///< three per triangle, each < positions.size()
        glm::vec4 color{0.8f, 0.8f, 0.8f, 1.0f};  ///< the material's baseColorFactor
    };
    std::vector<Triangles> triangles;
};

/// A skin (§3.7.3 Skins).
struct Skin {
    std::string name;
    std::vector<int> joints;                      ///< node indices, never empty
    std::vector<glm::mat4> inverse_bind_matrices; ///< one per joint, invertible (identity when absent)
    int skeleton = -1;                            ///< the skeleton root node, -1 when not given
};

/// What a channel animates (§3.11 Animations). Morph-target `weights` channels are not
/// kept (they do not move joints).
enum class Path { Translation, Rotation, Scale };

/// How a sampler interpolates between keys (§3.11, Appendix C).
enum class Interpolation { Linear, Step, CubicSpline };

/// Keyframes of one animated property.
struct Sampler {
    std::vector<float> times;       ///< strictly increasing, finite, at least one
    /// The output values, xyz for translation and scale, xyzw for rotations (glTF order
    /// in the file, stored here as x, y, z, w components of a vec4). CUBICSPLINE keeps the
    /// file's layout of three elements per key: in-tangent, value, out-tangent.
    std::vector<glm::vec4> values;
    Interpolation interpolation = Interpolation::Linear;
};

/// One animated property of one node.
struct Channel {
    int node = 0;
    Path path = Path::Translation;
    std::size_t sampler = 0;        ///< index into Animation::samplers
};

/// One animation clip.
struct Animation {
    std::string name;  ///< the file's, or "animation<index>" when it has none (scenes pick clips by name)
    std::vector<Channel> channels;
    std::vector<Sampler> samplers;
    float start = 0.0f;             ///< earliest key time over all samplers, s
    float end = 0.0f;               ///< latest key time over all samplers, s
};

/// A loaded, checked character: every index in it is in range, the nodes form trees,
/// every sampler has the number of values its interpolation needs.
struct Character {
    std::string source;             ///< the file it came from
    std::vector<Node> nodes;
    std::vector<int> roots;         ///< the root nodes of the displayed scene (§3.5.1)
    std::vector<int> order;         ///< every node, each after its parent
    std::vector<Skin> skins;
    std::vector<Animation> animations;
    std::vector<Mesh> meshes;
    /// The file's root-level `extensions` object as JSON text, "" when it has none. Kept
    /// verbatim (not checked) for readers of extensions such as VRM spring bones
    /// (read_vrm_springs()), so that this header does not depend on a JSON library.
    std::string extensions;
};

/// A pose: local TRS and world matrix of every node, indexed like Character::nodes.
struct Pose {
    std::vector<glm::vec3> translation;
    std::vector<glm::quat> rotation;
    std::vector<glm::vec3> scale;
    std::vector<glm::mat4> world;
};

/// The value of `sampler` at `time` (s), for a property on `path`. Times before the first
/// key or after the last take that key's value; a time equal to a key returns the key's
/// value unchanged. LINEAR rotations are slerped along the shorter arc; rotations are
/// normalized after CUBICSPLINE (Appendix C).
[[nodiscard]] KODAWARI_API glm::vec4 sample(const Sampler& sampler, Path path, float time);

/// The rest pose: every node's own TRS (or matrix), with world matrices.
[[nodiscard]] KODAWARI_API Pose rest_pose(const Character& character);

/// Sets `pose` to `character`'s animation `animation` at `time` (s): the rest pose with
/// every channel's value applied, then the world matrices. `animation` must be an index
/// into Character::animations. Reuses `pose`'s storage.
KODAWARI_API void evaluate(const Character& character, std::size_t animation, float time, Pose& pose);

/// Recomputes `pose.world` from its local TRS, parents first. A node given by a matrix
/// uses that matrix (load_character rejects animations of such nodes, §3.5.3).
KODAWARI_API void compute_world(const Character& character, Pose& pose);

/// The rigid part of a world matrix: its translation and the rotation of its columns
/// with the scale divided out (exact for matrices without shear).
[[nodiscard]] KODAWARI_API rods::Transform rigid_part(const glm::mat4& world);

}  // namespace kodawari::animation
