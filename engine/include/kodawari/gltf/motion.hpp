#pragma once
/// @file
/// Animation from elsewhere (issue 18): clips made for another skeleton, retargeted onto
/// a rigged character through the VRM humanoid bones (kodawari::io).
///
/// - VRM Animation (`.vrma`, glTF with the root extension VRMC_vrm_animation 1.0):
///   `humanoid.humanBones.<bone>.node` names the file's node of each humanoid bone; the
///   file's clip animates those nodes. Expressions and lookAt are not used (a warning).
/// - Any glTF clip (`.gltf`, `.glb`, `.vrm`) whose skeleton a humanoid map names: a VRM
///   file's own humanoid, or a name map file, JSON `{"hips": "mixamorig:Hips", ...}`
///   (humanoid bone name -> node name).
/// - The target: a VRM avatar (VRMC_vrm 1.0 or VRM 0.x humanoid) or any glTF character
///   with a name map.
///
/// The retargeting (retarget()) carries each bone's rotation over in its rest frame and
/// the hips' displacement scaled by the leg-length ratio; docs/motions.md gives the
/// equations and their references (VRMC_vrm_animation 1.0, "how_to_transform_human_pose";
/// VRMC_vrm 1.0 humanoid). The result is an ordinary animation::Animation of the target, so
/// clips, pose backends, export and crowds use it unchanged.
///
/// Errors: make_error(Error::Kind::InvalidInput, "<file>: <JSON path>: <what was
/// expected>"), naming the file the problem is in (the motion, the map or the target);
/// Error::Kind::Io when a file cannot be read. Nothing here throws.

#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

#include "kodawari/core/api.hpp"
#include "kodawari/animation/character.hpp"
#include "kodawari/core/result.hpp"

namespace kodawari::gltf {

/// The 55 humanoid bone names of VRMC_vrm 1.0 ("humanoid.md", "List of humanoid bones"),
/// in the specification's order (torso, head, legs, arms, fingers): parents before children.
[[nodiscard]] KODAWARI_API const std::vector<std::string_view>& humanoid_bone_names();

/// Whether VRMC_vrm 1.0 marks `bone` Required: hips, spine, head, the upper and lower
/// legs, feet, upper and lower arms and hands (15 bones). False for unknown names.
[[nodiscard]] KODAWARI_API bool is_required_humanoid_bone(std::string_view bone);

/// Which way a skeleton's model space faces. glTF 2.0 and VRM 1.0 (and VRM Animation)
/// models face +Z; VRM 0.x models face -Z.
enum class Facing { PlusZ, MinusZ };

/// One humanoid bone of a skeleton.
struct HumanBone {
    std::string name;  ///< a humanoid_bone_names() entry
    int node = -1;     ///< index into the Character's nodes
    /// Where it is declared, for messages: "<file>: <JSON path>"
    /// ("walk.vrma: $.extensions.VRMC_vrm_animation.humanoid.humanBones.hips").
    std::string where;
};

/// The humanoid bones of one skeleton.
struct HumanoidMap {
    /// Where the map came from, for messages: "<file>: <JSON path>" of the object that
    /// lists the bones.
    std::string where;
    std::vector<HumanBone> bones;  ///< in humanoid_bone_names() order; each bone and node once
    Facing facing = Facing::PlusZ;
    std::vector<std::string> warnings;  ///< what was read but not used, each naming the file and JSON path

    /// The bone called `name`, nullptr when the map has none.
    [[nodiscard]] KODAWARI_API const HumanBone* find(std::string_view name) const;
};

/// The humanoid of a VRM Animation: `$.extensions.VRMC_vrm_animation` of `animation`
/// (a loaded .vrma). Errors: no such extension, `specVersion` not "1.0" (or
/// "1.0-draft"), no `humanoid.humanBones` or none in it, a node index that is not an
/// integer in range, a node used by two bones. Warnings: bones that are not VRM humanoid
/// bone names, leftEye / rightEye (the spec gives eyes to lookAt), `expressions`, `lookAt`.
[[nodiscard]] KODAWARI_API Result<HumanoidMap> read_vrm_animation_humanoid(const animation::Character& animation);

/// The humanoid of a VRM model: VRMC_vrm 1.0's `humanoid.humanBones` (facing +Z), else
/// VRM 0.x's `humanoid.humanBones[]` (facing -Z; its thumb bones renamed to 1.0's:
/// thumbProximal -> thumbMetacarpal, thumbIntermediate -> thumbProximal). Errors: neither
/// extension, node indices out of range or repeated.
[[nodiscard]] KODAWARI_API Result<HumanoidMap> read_vrm_humanoid(const animation::Character& character);

/// A name map file, `{"<humanoid bone>": "<node name>", ...}`, applied to `character`.
/// Facing: -Z when `character` is a VRM 0.x file, else +Z. Errors (naming `map_path` and
/// the key): not a JSON object, a key that is not a humanoid bone name, a value that is
/// not a string, a node name that no node (or more than one) of `character` has, a node
/// named for two bones, an empty map.
[[nodiscard]] KODAWARI_API Result<HumanoidMap> read_humanoid_name_map(const std::string& map_path,
                                                                     const animation::Character& character);

/// The most keys one retargeted channel may have (bounds the memory of a motion).
inline constexpr std::size_t kMaxMotionKeys = 100'000;
/// The longest gap between two keys of a retargeted channel, s (VRMC_vrm_animation 1.0
/// suggests 30 frames per second for LINEAR clips).
inline constexpr double kMotionKeyGap = 1.0 / 30.0;

/// What retarget() made.
struct Retargeted {
    animation::Animation animation;  ///< channels on the target's nodes only, every sampler LINEAR
    std::vector<std::string> warnings;
    float leg_ratio = 1.0f;    ///< the hips displacement's scale (see docs/motions.md)
    std::size_t bones = 0;     ///< humanoid bones given a rotation channel
    std::size_t keys = 0;      ///< keys per channel
};

/// Retargets clip `clip` of `source` (whose humanoid is `source_map`) onto `target` (whose
/// humanoid is `target_map`), as a clip called `name`. Keys: every key time of the source
/// clip, with gaps longer than kMotionKeyGap split evenly; LINEAR. A rotation channel for
/// every bone both maps have whose source node or a source ancestor is rotated by the
/// clip; a translation channel for the hips when the clip moves the hips' node or an
/// ancestor. Errors: no bone in common; a bone the clip animates that the target lacks and
/// VRM requires; more than kMaxMotionKeys keys. An optional bone the target lacks is a
/// warning. Deterministic: the same inputs give the same bits.
[[nodiscard]] KODAWARI_API Result<Retargeted> retarget(const animation::Character& source, std::size_t clip, const HumanoidMap& source_map,
                                                       const animation::Character& target, const HumanoidMap& target_map,
                                                       const std::string& name);

/// A motion as a scene or `kodawari rig --motion` names it (docs/scene-format.md,
/// "Motions of a rigged character"). Paths as given (already resolved by the caller).
struct MotionRequest {
    std::string name;        ///< the clip's name on the target
    std::string file;        ///< .vrma, .gltf, .glb or .vrm
    std::string clip;        ///< the source clip by name; "": the file's first (VRMC_vrm_animation)
    std::string map;         ///< a name map for the source skeleton; "": its VRMA / VRM humanoid
    std::string target_map;  ///< a name map for the target; "": its VRM humanoid
};

/// Which key of a MotionRequest an error of load_motion() is about.
enum class MotionKey { File, Clip, Map, TargetMap };

/// Loads `request.file`, finds its humanoid (the map, else VRMC_vrm_animation, else a VRM
/// humanoid) and the clip, the target's humanoid (target_map, else its VRM humanoid), and
/// retargets. On error, `*key` (when given) says which request key it is about. The
/// warnings of the maps are added to the result's.
[[nodiscard]] KODAWARI_API Result<Retargeted> load_motion(const MotionRequest& request, const animation::Character& target,
                                                          MotionKey* key = nullptr);

}  // namespace kodawari::gltf
