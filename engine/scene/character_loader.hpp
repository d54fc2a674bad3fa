#pragma once
/// @file
/// The version-2 parts of the scene format (docs/scene-format.md): characters, crowds
/// and the moving camera. Used by scene_loader.cpp; errors follow its style (file, JSON
/// path, what was expected).

#include <array>
#include <functional>
#include <numbers>
#include <string>
#include <vector>

#include <kodawari/rods/world.hpp>
#include <kodawari/scene/scene.hpp>

#include "scene/json_reader.hpp"

namespace kodawari::scene_detail {

/// The most character instances and chain instances one scene may hold (they bound the
/// memory of the rod state: about 3.5 kB per chain).
inline constexpr std::uint64_t kMaxCharacterInstances = 100'000;
inline constexpr std::uint64_t kMaxChainInstances = 1'000'000;
/// The most joints, chains and motions of one character.
inline constexpr std::size_t kMaxPerCharacter = 64;
/// The most colliders of one character; one chain touches at most rods::kMaxChainColliders
/// of them (its `colliders` list, or all of them).
inline constexpr std::size_t kMaxCharacterColliders = rods::kMaxCharacterColliders;
/// The ranges of the values the loaders read (shared so that every file checks alike).
inline constexpr double kDegToRad = std::numbers::pi / 180.0;
inline constexpr double kMaxCoordinate = 1e6;  // world positions (m), as the bird loader
inline constexpr double kMaxLocal = 1000.0;    // offsets inside a character (m)
inline constexpr double kMaxShape = 100.0;     // chain shape coordinates (m)
inline constexpr double kMaxTime = 1e5;        // motion times (s)

// Readers shared by the procedural characters (character_loader.cpp) and the rigged
// ones (rigged_character_loader.cpp); each reports errors at the node's JSON path.

/// A point as the scene stores it (CameraSpec's arrays) as a vector.
[[nodiscard]] glm::vec3 to_vec(const std::array<float, 3>& a);
/// [x, y, z], each coordinate in [-limit, limit].
[[nodiscard]] Result<glm::vec3> read_point(const JsonReader& r, const JsonNode& node, double limit);
/// A direction: any finite non-zero vector, normalized.
[[nodiscard]] Result<glm::vec3> read_direction(const JsonReader& r, const JsonNode& node);
/// An angle in degrees within `range`, returned in radians.
[[nodiscard]] Result<float> read_degrees(const JsonReader& r, const JsonNode& node, const NumberRange& range);
/// A time in s, in [0, kMaxTime].
[[nodiscard]] Result<float> read_time(const JsonReader& r, const JsonNode& node);
/// {"axis": [x, y, z], "angle_deg": a}: a rotation about a direction.
[[nodiscard]] Result<glm::quat> read_rotation(const JsonReader& r, const JsonNode& node);
/// {"position": [x, y, z], "rotation": {"axis": [...], "angle_deg": a}}, both optional.
[[nodiscard]] Result<rods::Transform> read_transform(const JsonReader& r, const JsonNode& node);
/// The index of the joint called `name`, or an error at `node` listing the joints.
[[nodiscard]] Result<std::uint32_t> find_joint(const JsonReader& r, const JsonNode& node, const rods::Skeleton& skeleton);
/// A name that may become part of "bunny#12/ear_l": non-empty, no '#' or '/'.
[[nodiscard]] Result<std::string> read_name(const JsonReader& r, const JsonNode& node);
/// An array of min..max elements; `what` describes a valid one.
[[nodiscard]] Result<std::size_t> read_array(const JsonReader& r, const JsonNode& node, std::size_t min, std::size_t max,
                                             const std::string& what);
/// `"a", "b", "c"`, for messages that list the valid names.
[[nodiscard]] std::string quoted_list(const std::vector<std::string>& names);
/// The index in `names` of the string at `node`; otherwise an error at `node` expecting
/// `what` and listing the names.
[[nodiscard]] Result<std::uint32_t> find_name(const JsonReader& r, const JsonNode& node, const std::vector<std::string>& names,
                                              const std::string& what);
/// The index of the animation of `character` named by the string at `node`
/// (rigged_character_loader.cpp).
[[nodiscard]] Result<std::int32_t> find_clip(const JsonReader& r, const JsonNode& node, const animation::Character& character);
/// The `physics` object, over the values already in `p`.
[[nodiscard]] Result<void> read_physics(const JsonReader& r, const JsonNode& node, rods::SolverParams& p);
/// A `wind` object (rods::WindField), over the values already in `w` (a character's
/// over the scene's).
[[nodiscard]] Result<void> read_wind(const JsonReader& r, const JsonNode& node, rods::WindField& w);
/// A view example whose shape has `joints` joints.
[[nodiscard]] Result<ViewSpec> read_view(const JsonReader& r, const JsonNode& node, std::size_t joints);
/// The optional `colliders` member of a character `node`: at most kMaxCharacterColliders
/// spheres, capsules (outside or `inside`) and planes, each on the joint whose index
/// `joint` returns for its `joint` member, names unique.
[[nodiscard]] Result<std::vector<ColliderSpec>> read_colliders(const JsonReader& r, const JsonNode& node,
                                                               const std::function<Result<std::uint32_t>(const JsonNode&)>& joint);
/// What a chain's settings need of its character: its joints (skeleton joints or glTF
/// nodes) for keyed examples and `center`, its colliders' names for `colliders`.
struct JointLookup {
    std::function<Result<std::uint32_t>(const JsonNode&)> find;  ///< the joint a name at the node names
    std::function<std::int32_t(std::uint32_t)> parent;          ///< -1 for a root
    /// In the rest pose, relative to the parent, as a Pose key source measures it.
    std::function<glm::quat(std::uint32_t)> rest_rotation;
    std::uint32_t reference = 0;  ///< the character's reference joint (motion keys' default)
    std::vector<std::string> colliders;  ///< the character's colliders' names, in order ("" unnamed)
};
/// JointLookup::colliders of `colliders`.
[[nodiscard]] std::vector<std::string> collider_names(const std::vector<ColliderSpec>& colliders);
/// A shape: {"positions": [...], "orientations": [...]} or {"arc": {...}}, of `joints`
/// joints (0: any in 2..32, for a base shape) (chain_loader.cpp).
[[nodiscard]] Result<rods::ChainShape> read_shape(const JsonReader& r, const JsonNode& node, std::size_t joints);
/// A unit quaternion [x, y, z, w] (length within 1e-3 of 1), normalized.
[[nodiscard]] Result<glm::quat> read_unit_quat(const JsonReader& r, const JsonNode& node);
/// A chain's `thickness`, `mass`, `physics`, `collide`, `colliders`, `center`, `views`
/// and `keyed` over the values already in `c` (its base shape set), then check_template().
[[nodiscard]] Result<void> read_chain_settings(const JsonReader& r, const JsonNode& node, const JointLookup& joints,
                                               ChainSpec& c);
/// A chain's `keyed` array (docs/keyed-examples.md, keyed_loader.cpp): its keyed examples
/// and the key sources they read, into `c`.
[[nodiscard]] Result<void> read_keyed(const JsonReader& r, const JsonNode& node, const JointLookup& joints, ChainSpec& c);
/// The chain's template (views and keyed examples), named `name`.
[[nodiscard]] Result<rods::ChainTemplate> make_template(const std::string& name, const ChainSpec& chain);
/// Builds the chain's template once, so that a bad shape is reported where it is written.
[[nodiscard]] Result<void> check_template(const JsonReader& r, const JsonNode& node, const ChainSpec& chain);

/// A chain of a procedural character on a joint of `skeleton`, its physics over
/// `defaults`; appended to `chains`, with its mirrored copy when it names one
/// (chain_loader.cpp).
[[nodiscard]] Result<void> read_chain(const JsonReader& r, const JsonNode& node, const rods::Skeleton& skeleton,
                                      const std::vector<ColliderSpec>& colliders, const rods::SolverParams& defaults,
                                      std::vector<ChainSpec>& chains);

/// A character with `gltf` (docs/scene-format.md, "Rigged characters"): the file loaded
/// relative to the scene's folder, chains by node names with base shapes from its rest
/// pose, colliders on its nodes.
[[nodiscard]] Result<CharacterSpec> read_rigged_character(const JsonReader& r, const JsonNode& node);

/// Reads `characters` (a non-empty array) and `crowds` (absent: one instance of every
/// character at the origin) into `scene`.
[[nodiscard]] Result<void> read_characters(const JsonReader& r, const JsonNode& characters, const JsonNode& crowds,
                                           Scene& scene);

/// Reads the camera's version-2 keys (`projection`, `orbit`, `path`, `keyframes`) into
/// camera.motion, after read_camera has read `position`, `target` and `fov_deg`
/// (camera_loader.cpp).
[[nodiscard]] Result<void> read_camera_motion(const JsonReader& r, const JsonNode& node, CameraSpec& camera);

}  // namespace kodawari::scene_detail
