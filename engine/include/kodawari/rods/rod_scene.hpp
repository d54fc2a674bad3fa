#pragma once
/// @file
/// A scene's characters as the rod backends run them (SPEC A, C): one chain template per
/// chain of each character, one chain instance per chain of each character instance, and
/// the kinematic model (skeletons, procedural motions, instance placements, the camera)
/// that produces every frame's input on demand. Part of kodawari::sim; building one from a
/// scene file is kodawari/scene/scene.hpp's build_rod_scene (kodawari::io).

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>

#include "kodawari/core/api.hpp"
#include "kodawari/animation/character.hpp"
#include "kodawari/rods/kinematics.hpp"
#include "kodawari/rods/world.hpp"

namespace kodawari {

using KeyJoint = rods::KeyJoint;

/// A chain of a character template: where its root sits on the skeleton.
struct ChainAttachment {
    std::uint32_t joint = 0;  ///< skeleton joint
    rods::Transform offset;   ///< the chain root's frame in the joint's frame
    bool collide = true;      ///< false: the chain instance gets no colliders
    /// Its colliders: CharacterKinematics::colliders[collider_begin, collider_begin +
    /// collider_count) (each chain's set is one run there; chains with the same set share it).
    std::uint32_t collider_begin = 0;
    std::uint32_t collider_count = 0;
    /// The joint whose space its inertia is measured in (rods::follow_center), -1 for none.
    std::int32_t center = -1;
    /// Its key sources, in its template's key_sources order (RodFrame::keys).
    std::vector<KeyJoint> keys;
};

/// A collider of a character template, in its joint's frame (rods::Collider's meaning of
/// a, b and radius for its kind: a plane's b is its normal in the joint's frame).
struct ColliderAttachment {
    std::uint32_t joint = 0;
    glm::vec3 a{0.0f}, b{0.0f};
    float radius = 0.0f;
    rods::ColliderKind kind = rods::ColliderKind::Outside;
};

/// The kinematic model of one character template: a procedural skeleton and motions,
/// or a rigged glTF character (`rig` set) whose animation clips pose its nodes. For a
/// rigged character, joint indices (chain attachments, colliders, skeleton.reference)
/// are node indices, skeleton.joints is empty, and a chain's root frame is its root
/// node's world transform with the scale removed (animation::rigid_part).
struct CharacterKinematics {
    std::string name;
    rods::Skeleton skeleton;
    rods::CharacterMotion motion;
    std::shared_ptr<const animation::Character> rig;
    std::vector<std::vector<int>> chain_nodes;  ///< rigged: per chain its nodes, root first
    /// Rigged: per node, (chain, joint) when it is a simulated joint (joint >= 1) of one of
    /// the chains, else (-1, -1).
    std::vector<std::pair<int, int>> simulated_joint;
    std::vector<ChainAttachment> chains;        ///< chain k uses RodWorld template first_template + k
    std::vector<ColliderAttachment> colliders;
    std::uint32_t first_template = 0;
    std::vector<std::string> joint_names;       ///< skeleton order (parents first)
    std::vector<std::int32_t> joint_parents;    ///< -1 for the root
};

/// One character instance (SPEC C).
struct CharacterInstance {
    std::uint32_t character = 0;  ///< index into RodScene::characters
    rods::Transform placement;    ///< the instance's transform (position, yaw)
    float time_offset = 0.0f;     ///< s, added to the scene time for its motions
    std::int32_t clip = -1;       ///< rigged characters: the clip it plays (looping), -1 = rest pose
    std::uint32_t chain_begin = 0;     ///< its chains: RodWorld::chains[begin, begin + chain count)
    std::uint32_t collider_begin = 0;  ///< its colliders: RodFrame::colliders[begin, begin + collider count)
    std::uint32_t center_begin = 0;    ///< its chains' centers: RodFrame::centers[begin, ...), chain by chain
};

/// The characters of a scene, ready for the rod backends.
struct KODAWARI_API RodScene {
    /// Templates (one per character chain, "bunny/ear_l"), chains (one per chain per
    /// instance, instance by instance), counts finalized.
    rods::RodWorld world;
    std::vector<std::string> character_names;  ///< per character instance, "bunny#12"
    std::vector<std::string> chain_names;      ///< per chain instance, "bunny#12/ear_l"
    float fps = 60.0f;
    std::uint32_t frames = 1;  ///< the scene's frame count; frames 0 .. frames - 1
    std::vector<CharacterKinematics> characters;  ///< templates
    std::vector<CharacterInstance> instances;     ///< world.character_count of them
    /// The whole scene's index of instances[0]: 0, or where slice() began. What a rule
    /// per instance keys on (the clips' rate of posed characters, CrowdAnimator), so that
    /// a shard's instances follow it as in the whole scene.
    std::uint32_t first_instance = 0;
    rods::CameraMotion camera;
    float fov_deg = 50.0f;  ///< vertical field of view, for renderers and projections
    /// The wind fields every frame gives (world.wind_count of them): [0] the scene's
    /// (calm when it has none), then the characters' own; ChainInstance::wind picks.
    std::vector<rods::WindField> winds;

    /// The character instances [begin, end) alone, with their chains and colliders, the
    /// same templates, camera and timing: what one shard of a bake simulates (issue 15).
    /// Each instance keeps its placement, time offset and clip, so its frames are those
    /// of the whole scene bit for bit; the sliced instance i is this scene's begin + i.
    /// Asserts begin <= end <= instances.size().
    [[nodiscard]] RodScene slice(std::uint32_t begin, std::uint32_t end) const;
    /// The time of frame `index`: index / fps, s.
    [[nodiscard]] float time(std::uint32_t index) const;

    /// The kinematic input of frame `index` (time = index / fps; dt = 1 / fps; frame 0 is
    /// the initial pose: start the chains with rods::initial_state from it, then step
    /// with frames 1, 2, ...). Deterministic: the same index gives the same bits.
    [[nodiscard]] rods::RodFrame frame(std::uint32_t index) const;
    /// As frame(index), into `out`, reusing its storage (no allocation once it has the
    /// right sizes): the per-frame path for large crowds.
    void frame(std::uint32_t index, rods::RodFrame& out) const;
    /// As frame(index, out), but with `rigged` false the rigged instances' entries are
    /// left for the caller to fill with rigged_frame() (a pose backend's poses).
    void kinematic_frame(std::uint32_t index, rods::RodFrame& out, bool rigged) const;

    /// The camera at frame `index` (position, target, forward); with fov_deg it gives a
    /// look-at + perspective projection.
    [[nodiscard]] rods::CameraPose camera_pose(std::uint32_t index) const;

    /// World transforms of every skeleton joint of character instance `c` at frame
    /// `index`, in joint_names(c) order (for export and rendering).
    [[nodiscard]] std::vector<rods::Transform> joint_poses(std::uint32_t c, std::uint32_t index) const;
    /// As joint_poses(c, index), into `out` (resized to the joint count).
    void joint_poses(std::uint32_t c, std::uint32_t index, std::vector<rods::Transform>& out) const;
    /// The skeleton joint names of character instance `c`.
    [[nodiscard]] const std::vector<std::string>& joint_names(std::uint32_t c) const;
    /// The parent of each skeleton joint of character instance `c` (-1 for the root).
    [[nodiscard]] const std::vector<std::int32_t>& joint_parents(std::uint32_t c) const;
    /// The chain instances of character instance `c`: world.chains[first, first + count).
    [[nodiscard]] std::uint32_t chain_count(std::uint32_t c) const;

    /// The time at which rigged instance `c` samples its clip at frame `index`: the
    /// scene time plus its offset, wrapped into the clip's [start, end] (clips loop).
    [[nodiscard]] float clip_time(std::uint32_t c, std::uint32_t index) const;
    /// Rigged instance `c`'s entries of `out` (reference, chain roots, colliders) from
    /// its nodes' world matrices `nodes` (placement included, as a pose backend returns
    /// them). frame() does this with animation::evaluate; a GPU pose backend feeds it too.
    void rigged_frame(std::uint32_t c, std::span<const glm::mat4> nodes, rods::RodFrame& out) const;

    /// Rigged instance `c`'s node world matrices at frame `index` (placement included,
    /// indexed like its Character::nodes) with the simulated chain joints where the rod
    /// backend put them: `positions` and `orientations` are a ChainSnapshot's (the whole
    /// world's joints). A chain joint i >= 1 sits at its simulated position with its
    /// particle's orientation turned by the shortest arc that points its bone (the rest
    /// direction to joint i + 1, Chain::bone_axis) at the next joint (SPEC A.4's
    /// skinning output; the last joint keeps the particle's), and the node's animated
    /// local scale; every other node follows its parent with its clip pose. `pose` is
    /// scratch (it ends as the clip pose). What skinning and the rigged export use.
    void rigged_world(std::uint32_t c, std::uint32_t index, std::span<const glm::vec3> positions,
                      std::span<const glm::quat> orientations, animation::Pose& pose, std::vector<glm::mat4>& out) const;

private:
    // Rigged instance c's clip pose (local TRS and unplaced world) at frame `index`.
    void clip_pose(std::uint32_t c, std::uint32_t index, animation::Pose& pose) const;
    // Rigged instance c's node world matrices at frame `index` on the CPU, placement
    // included; `pose` is scratch.
    void rig_world(std::uint32_t c, std::uint32_t index, animation::Pose& pose, std::vector<glm::mat4>& nodes) const;
};

}  // namespace kodawari
