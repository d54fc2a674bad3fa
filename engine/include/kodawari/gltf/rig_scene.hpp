#pragma once
/// @file
/// One-command chain setup (SPEC A.7, issue 4; `kodawari rig`): from a rigged glTF / VRM
/// character to a scene file (docs/scene-format.md, "Rigged characters") that simulates
/// its chains, ready for `kodawari run`.
///
/// Where the chains come from, first rule that applies:
/// 1. RigOptions::search given (`--roots` or `--chains`): find_chains() with it.
/// 2. The file has VRM spring bones (read_vrm_springs()): one chain per spring, with its
///    mapped physics, and the springs' colliders (sphere, capsule, inside, plane).
/// 3. Otherwise find_chains() with the default name patterns.
/// Colliders in the scene are in their node's rigid frame (rest pose, metres), named
/// "collider<i>" after their index in the file, with their kind (outside, `inside`,
/// plane). Each VRM spring's chain lists the colliders of its own collider groups (at most
/// rods::kMaxChainColliders; a warning when a spring had more) and its `center`; chains
/// found by name patterns collide with all colliders. Nodes are named by name where it
/// is unique, else by their path of names from a root, else by index.

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "kodawari/core/api.hpp"
#include "kodawari/gltf/chains.hpp"
#include "kodawari/core/result.hpp"

namespace kodawari::gltf {

/// What `kodawari rig` is asked to do.
struct RigOptions {
    std::optional<ChainSearch> search;  ///< none: VRM springs, else the default patterns
    std::string clip;                   ///< the animation to play; "": the file's first (or the rest pose)
    std::string name;                   ///< the scene character's name; "": from the file name
    float duration = 10.0f;             ///< s, the scene's
    /// Clips made for other skeletons (`--motion`, gltf/motion.hpp): each file's first
    /// clip retargeted onto the character, named after the file's stem (made unique),
    /// listed under the character's `motions`; with no `clip`, the first one plays.
    std::vector<std::string> motions;
    /// A name map for the motions that are not VRM Animations (`--motion-map`); "": none.
    std::string motion_map;
};

/// One retargeted motion in the written scene.
struct RigMotion {
    std::string name;
    std::string file;           ///< as given
    std::size_t bones = 0;      ///< humanoid bones it rotates
    std::size_t keys = 0;       ///< keys per channel
    float duration = 0.0f;      ///< s
    bool hips = false;          ///< whether it moves the hips
    float leg_ratio = 1.0f;     ///< the hips displacement's scale
    bool mapped = false;        ///< through motion_map (else its VRM Animation humanoid)
};

/// One chain in the written scene.
struct RigChain {
    std::string name;
    std::string root;  ///< the root node's name
    std::uint32_t joints = 0;
    float length = 0.0f;     ///< m
    float thickness = 0.0f;  ///< m
};

/// What make_rig_scene() wrote and found.
struct RigScene {
    std::string json;  ///< the scene file's text
    std::string source;  ///< "VRM 1.0 spring bones", "VRM 0.x secondaryAnimation", "name patterns", "named roots"
    std::string reference;  ///< the reference joint's node name
    std::string clip;       ///< the clip instances play, "" for the rest pose
    std::vector<RigChain> chains;
    std::vector<RigMotion> motions;
    std::uint32_t colliders = 0;
    float size = 0.0f;  ///< character_size(), m
    std::vector<std::string> warnings;  ///< what could not be used, each naming the file
};

/// Loads `character_path` and writes the text of a scene that simulates it; the scene
/// refers to the character by its path relative to the folder of `scene_path` (where
/// the caller will write it). Errors: the file does not load, no chain is found, the
/// clip does not exist, a motion does not retarget (load_motion()'s errors). The scene
/// has one instance at the origin and a camera orbiting the head.
[[nodiscard]] KODAWARI_API Result<RigScene> make_rig_scene(const std::string& character_path, const std::string& scene_path,
                                                           const RigOptions& options);

}  // namespace kodawari::gltf
